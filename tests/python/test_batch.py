"""samp.batch on real Dask clusters: a `dask scheduler` and two `dask worker` processes on
127.0.0.1 started here (real TCP), and a LocalCluster. Outputs are compared byte for byte
with `samp fit` on the same sequence; a worker killed mid-run must not change them."""

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time

import pytest

from conftest import assert_same_files, make_sequence_root, shipped_model, tree_bytes

# Bound on every wait of this file (start-up, a run): generous for a loaded 2-core machine.
TIMEOUT = 240


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start(cmd, log):
    # Own process group: the worker's nanny and its worker process are killed together.
    return subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, start_new_session=True, env=os.environ.copy())


def stop(proc):
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=TIMEOUT)


def wait_for_workers(address, count):
    from distributed import Client
    with Client(address, timeout="%ds" % TIMEOUT) as client:
        client.wait_for_workers(count, timeout=TIMEOUT)
        return sorted(client.scheduler_info()["workers"])


@pytest.fixture
def dask_cluster(tmp_path):
    """A scheduler and two single-threaded workers, each its own process group."""
    port = free_port()
    address = "tcp://127.0.0.1:%d" % port
    logs = tmp_path / "logs"
    logs.mkdir()
    procs = []
    dask = [sys.executable, "-m", "dask"]
    try:
        procs.append(start(dask + ["scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                           open(logs / "scheduler.log", "w")))
        workers = []
        for i in range(2):
            p = start(dask + ["worker", address, "--nworkers", "1", "--nthreads", "1", "--no-dashboard",
                              "--local-directory", str(tmp_path / ("worker%d" % i)), "--name", "w%d" % i],
                      open(logs / ("worker%d.log" % i), "w"))
            procs.append(p)
            workers.append(p)
        wait_for_workers(address, 2)
        yield address, workers
    finally:
        for p in procs:
            stop(p)


def batch(args, **kw):
    return subprocess.Popen([sys.executable, "-m", "samp.batch"] + args, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, **kw)


def fit_args(scheduler, root, out, *extra):
    return ["fit", "--scheduler", scheduler, "--seq-root", root, "--out", out, "--model", shipped_model(),
            "--threads", "1", "--no-progress"] + list(extra)


def cli_fit(seq, out, *extra):
    r = subprocess.run([os.environ["SAMP_EXECUTABLE"], "fit", "--model", shipped_model(), "--seq", seq, "--out",
                        out, "--threads", "1"] + list(extra), capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 0, r.stderr
    return tree_bytes(out)


def assert_same_as_samp_fit(root, out, names, tmp_path, *extra):
    """OUT/NAME is byte for byte what `samp fit --seq ROOT/NAME --out OUT/NAME` writes:
    the batch output is moved aside, samp fit writes to the same paths, the trees compare."""
    aside = str(tmp_path / "batch_aside")
    shutil.move(out, aside)
    try:
        for name in names:
            expected = cli_fit(os.path.join(root, name), os.path.join(out, name), *extra)
            assert_same_files(tree_bytes(os.path.join(aside, name)), expected, name)
    finally:
        shutil.rmtree(out, ignore_errors=True)
        shutil.move(aside, out)


def test_fit_on_scheduler_and_two_worker_processes(dask_cluster, tmp_path):
    address, _ = dask_cluster
    root = str(tmp_path / "seqs")
    names = make_sequence_root(root, 4)
    out = str(tmp_path / "out")
    p = batch(fit_args(address, root, out, "--set", "fit.em_iterations=1", "--summary-file"))
    stdout, stderr = p.communicate(timeout=TIMEOUT)
    assert p.returncode == 0, stderr
    assert "4 sequence(s) (0 failed), 4 track(s) fitted" in stdout
    assert sorted(os.listdir(out)) == sorted(names + ["batch_summary.json"])
    with open(os.path.join(out, "batch_summary.json")) as f:
        summary = json.load(f)
    assert len({s["pid"] for s in summary["sequences"]}) == 2  # both worker processes fitted
    # The task thread's CPU time: positive, and not above its wall time (one thread).
    assert all(0 < s["cpu_seconds"] <= s["seconds"] + 0.05 for s in summary["sequences"])
    os.remove(os.path.join(out, "batch_summary.json"))
    assert_same_as_samp_fit(root, out, names, tmp_path, "--em-iterations", "1")


def test_killing_a_worker_mid_run_fits_every_sequence_once(dask_cluster, tmp_path):
    address, workers = dask_cluster
    root = str(tmp_path / "seqs")
    names = make_sequence_root(root, 10)
    out = str(tmp_path / "out")
    p = batch(fit_args(address, root, out))
    # Kill one worker (nanny and worker process, SIGKILL) as soon as the first
    # sequence is committed, while the others are queued or running.
    deadline = time.time() + TIMEOUT
    while time.time() < deadline and p.poll() is None:
        if os.path.isdir(out) and any(n in names for n in os.listdir(out)):
            break
        time.sleep(0.02)
    committed_at_kill = [n for n in os.listdir(out) if n in names] if os.path.isdir(out) else []
    stop(workers[0])
    stdout, stderr = p.communicate(timeout=TIMEOUT)
    assert len(committed_at_kill) < len(names), "the run ended before the kill"
    assert p.returncode == 0, stderr
    assert "10 sequence(s) (0 failed), 10 track(s) fitted" in stdout
    # Exactly one output per sequence and nothing else (no staging folder left).
    assert sorted(os.listdir(out)) == sorted(names)
    assert_same_as_samp_fit(root, out, names, tmp_path)


def test_fit_on_a_local_cluster_reports_failures_and_exits_1(tmp_path):
    root = str(tmp_path / "seqs")
    names = make_sequence_root(root, 2)
    # A sequence folder that cannot be read: its fit fails, the others complete.
    os.makedirs(os.path.join(root, "broken", "calib"))
    out = str(tmp_path / "out")
    p = batch(fit_args("local", root, out, "--workers", "2"))
    stdout, stderr = p.communicate(timeout=TIMEOUT)
    assert p.returncode == 1, stderr
    assert "3 sequence(s) (1 failed), 2 track(s) fitted" in stdout
    assert "FAILED broken: every sequence failed" in stdout
    # samp fit exits 1 on the broken one too, and writes the same files.
    r = subprocess.run([os.environ["SAMP_EXECUTABLE"], "fit", "--model", shipped_model(), "--seq",
                        os.path.join(root, "broken"), "--out", str(tmp_path / "cli_broken"), "--threads", "1"],
                       capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 1
    assert sorted(tree_bytes(str(tmp_path / "cli_broken"))) == sorted(tree_bytes(os.path.join(out, "broken")))
    assert_same_as_samp_fit(root, out, names, tmp_path)


def test_bad_arguments_exit_non_zero_with_the_field(tmp_path):
    root = str(tmp_path / "seqs")
    make_sequence_root(root, 1)
    p = batch(fit_args("local", root, str(tmp_path / "out"), "--set", "fit.em_iterations=-1"))
    _, stderr = p.communicate(timeout=TIMEOUT)
    assert p.returncode == 1
    assert "FitOptions.em_iterations must be >= 0" in stderr
    p = batch(fit_args("local", root, str(tmp_path / "out"), "--set", "fit.no_such=1"))
    _, stderr = p.communicate(timeout=TIMEOUT)
    assert p.returncode == 1 and "fit.no_such" in stderr


def test_fit_of_a_kitti_tracking_folder_matches_samp_fit(tmp_path):
    """--kitti-tracking ROOT --sequence all --frames --detections: one task per sequence of
    KITTI tracking's own layout (written by samp synth --layout kitti-tracking), OUT/NAME
    byte for byte what samp fit --kitti-tracking ROOT --sequence NAME writes."""
    cad = tmp_path / "cad"
    cad.mkdir()
    for i, (l, h, w) in enumerate([(4.2, 1.5, 1.8), (3.9, 1.45, 1.7), (4.6, 1.6, 1.85)]):
        write_box_obj(str(cad / ("box%d.obj" % i)), l, h, w)
    kitti = str(tmp_path / "kitti")
    r = subprocess.run([os.environ["SAMP_EXECUTABLE"], "synth", "--cad", str(cad), "--layout", "kitti-tracking",
                        "--preset", "clean", "--sequences", "2", "--frames", "5", "--cars-per-sequence", "2",
                        "--seed", "7", "-o", kitti, "-q"], capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 0, r.stderr
    root = os.path.join(kitti, "training")
    detections = os.path.join(kitti, "detections")
    assert sorted(os.listdir(os.path.join(root, "image_02"))) == ["0000", "0001"]
    out = str(tmp_path / "out")
    source = ["--kitti-tracking", root, "--frames", "1-4", "--detections", detections]
    p = batch(["fit", "--scheduler", "local", "--workers", "1", "--out", out, "--model", shipped_model(),
               "--threads", "1", "--no-progress"] + source)
    stdout, stderr = p.communicate(timeout=TIMEOUT)
    assert p.returncode == 0, stderr
    assert "2 sequence(s) (0 failed)" in stdout
    assert sorted(os.listdir(out)) == ["0000", "0001"]
    with open(os.path.join(out, "0000", "label_02", "0000.txt")) as f:
        frames = {int(line.split()[0]) for line in f if line.strip()}
    assert frames and min(frames) >= 1 and max(frames) <= 4
    aside = str(tmp_path / "aside")
    shutil.move(out, aside)
    for name in ("0000", "0001"):
        r = subprocess.run([os.environ["SAMP_EXECUTABLE"], "fit", "--model", shipped_model(), "--kitti-tracking",
                            root, "--sequence", name, "--frames", "1-4", "--detections", detections, "--out",
                            os.path.join(out, name), "--threads", "1"],
                           capture_output=True, text=True, timeout=TIMEOUT)
        assert r.returncode == 0, r.stderr
        assert_same_files(tree_bytes(os.path.join(aside, name)), tree_bytes(os.path.join(out, name)), name)
        assert os.path.isfile(os.path.join(aside, name, "detector_model.png"))  # drawn on the worker
    # --sequence picks, and is refused without a KITTI source; --no-detector-plot as samp fit's.
    p = batch(["fit", "--scheduler", "local", "--workers", "1", "--out", str(tmp_path / "one"), "--model",
               shipped_model(), "--threads", "1", "--no-progress", "--kitti-tracking", root, "--sequence", "1",
               "--detections", detections, "--set", "fit.em_iterations=0", "--no-detector-plot"])
    stdout, stderr = p.communicate(timeout=TIMEOUT)
    assert p.returncode == 0, stderr
    assert sorted(os.listdir(str(tmp_path / "one"))) == ["0001"]
    one = os.path.join(str(tmp_path / "one"), "0001")
    assert os.path.isfile(os.path.join(one, "detector_model.json"))
    assert not os.path.exists(os.path.join(one, "detector_model.png"))
    with open(os.path.join(one, "config.json")) as f:
        assert json.load(f)["detector_plot"] is False
    p = batch(fit_args("local", root, str(tmp_path / "two")) + ["--sequence", "0001"])
    _, stderr = p.communicate(timeout=TIMEOUT)
    assert p.returncode == 2 and "--sequence names sequences of --kitti-tracking" in stderr
    p = batch(["fit", "--scheduler", "local", "--out", str(tmp_path / "three"), "--model", shipped_model(),
               "--kitti-tracking", root, "--frames", "9-3"])
    _, stderr = p.communicate(timeout=TIMEOUT)
    assert p.returncode == 1 and "--frames '9-3': first after last" in stderr


# ------------------------------------------------------------------ train

def write_box_obj(path, length, height, width):
    l, h, w = length / 2, height, width / 2
    v = [(x, y, z) for x in (-l, l) for y in (0.0, h) for z in (-w, w)]
    faces = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
    with open(path, "w") as f:
        for p in v:
            f.write("v %g %g %g\n" % p)
        for q in faces:
            f.write("f %d %d %d\nf %d %d %d\n" % (q[0], q[1], q[2], q[0], q[2], q[3]))


def test_train_on_a_local_cluster_matches_samp_train(tmp_path):

    import numpy as np

    import samp
    cad = tmp_path / "cad"
    cad.mkdir()
    sizes = [(3.8, 1.4, 1.7), (4.2, 1.5, 1.8), (4.6, 1.6, 1.8), (5.0, 1.8, 1.9), (4.0, 1.7, 1.6), (4.8, 1.4, 2.0)]
    for i, (l, h, w) in enumerate(sizes):
        write_box_obj(str(cad / ("box%d.obj" % i)), l, h, w)
    # A file that is no mesh: rejected on the worker, reported, not trained on.
    (cad / "broken.obj").write_text("not a mesh\n")
    fields = {"scan": {"num_views": 24, "width": 96, "height": 96},
              "grid": {"voxel_size": 0.2, "dims": [31, 15, 15], "origin": [-3.0, -2.3, -1.4]},
              "pca": {"num_components": 3}, "num_threads": 1}
    config = tmp_path / "train.json"
    config.write_text(json.dumps(fields))
    distributed = str(tmp_path / "distributed.vdb")
    p = batch(["train", str(cad), "-o", distributed, "--scheduler", "local", "--workers", "2",
               "--config", str(config), "--no-progress"])
    stdout, stderr = p.communicate(timeout=TIMEOUT)
    assert p.returncode == 0, stderr
    assert "6 of 7 models used, R = 3" in stdout
    assert "skipping broken.obj" in stderr
    # Blocks of 4 grids: the Gram matrix from 3 block tasks, the products summed over 2.
    blocked = str(tmp_path / "blocked.vdb")
    p = batch(["train", str(cad), "-o", blocked, "--scheduler", "local", "--workers", "2",
               "--config", str(config), "--block", "4", "--no-progress"])
    _, stderr = p.communicate(timeout=TIMEOUT)
    assert p.returncode == 0, stderr
    options = samp.TrainOptions().from_dict(fields)
    options.show_progress = False
    local = str(tmp_path / "local.vdb")
    samp.train(str(cad), local, options)
    b = samp.ShapeModel.load(local)

    def rel(x, y):
        return np.max(np.abs(x.astype(np.float64) - y)) / np.max(np.abs(y))

    for path in (distributed, blocked):
        a = samp.ShapeModel.load(path)
        assert a.training_shapes == b.training_shapes
        assert a.train_options == b.train_options
        # The same double sums for the mean: identical.
        np.testing.assert_array_equal(a.mean, b.mean)
        assert rel(a.eigenvalues, b.eigenvalues) < 1e-5, path
        assert rel(a.components, b.components) < 1e-5, path
        assert abs(a.total_variance - b.total_variance) <= 1e-5 * b.total_variance
    # Too few usable models for R: the trainer's error, exit status 1.
    p = batch(["train", str(cad), "-o", str(tmp_path / "x.vdb"), "--scheduler", "local", "--workers", "1",
               "--config", str(config), "--components", "6", "--no-progress"])
    _, stderr = p.communicate(timeout=TIMEOUT)
    assert p.returncode == 1
    assert "only 6 of 7 models are usable; a model with R = 6 components needs at least 7" in stderr


def test_local_cluster_runs_its_workers_with_the_quiet_housekeeping():
    """--scheduler local: the worker processes get the malloc environment and Dask's slowed-down
    housekeeping (no stack profiler, no work stealing); LOCAL_CLUSTER_CONFIG says why."""
    import argparse

    from samp import batch as driver

    def worker_view():
        import dask
        return ({k: dask.config.get(k) for k in driver.LOCAL_CLUSTER_CONFIG},
                {k: os.environ.get(k) for k in driver.WORKER_MALLOC_ENVIRON})

    client, cluster = driver._client(argparse.Namespace(scheduler="local", workers=1, connect_timeout="60s"))
    try:
        views = list(client.run(worker_view).values())
        assert len(views) == 1
        config, environ = views[0]
        assert config == driver.LOCAL_CLUSTER_CONFIG
        assert environ == driver.WORKER_MALLOC_ENVIRON
        assert client.run_on_scheduler(lambda dask_scheduler: "stealing" in dask_scheduler.extensions) is False
    finally:
        client.close()
        cluster.close()
