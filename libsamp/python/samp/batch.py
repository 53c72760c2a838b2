"""Fitting many sequences on a Dask cluster (docs/cluster.md).

    python3 -m samp.batch fit --scheduler ADDRESS|local --seq-root ROOT --out OUT \\
        --model MODEL.vdb [--threads N] [--config CONFIG.json] [--set fit.em_iterations=2 ...]
    python3 -m samp.batch fit --scheduler ... --kitti-tracking ROOT [--sequence all|0004,0011] \\
        [--frames 100-300] [--detections FILE|DIR] --out OUT --model MODEL.vdb

Every sequence is one task: each folder directly under ROOT that has a calib/
folder (--seq-root), or each sequence of a KITTI tracking or KITTI stereo
folder in its own layout (--kitti-tracking, --kitti-stereo with --sequence,
listed as samp fit lists them). On a worker the task runs RunFit, the
function behind `samp fit`, with that one sequence and output_dir = OUT/NAME,
so OUT/NAME holds exactly what `samp fit --seq ROOT/NAME --out OUT/NAME [the
same options]` (or `samp fit --kitti-tracking ROOT --sequence NAME ...`) writes (but
for the wall-clock times in tracks.json, which differ from run to run)
(written into a temporary folder and renamed into place, so a worker that dies
leaves no half-written output). Dask reschedules the task of a worker that
died (the scheduler's distributed.scheduler.allowed-failures, default 3); the
rerun replaces whatever the first attempt committed.

Exit status as `samp fit`: 0 when every sequence was fitted, 1 when any failed
(each failure is listed at the end), 2 for bad arguments.
"""

import argparse
import json
import os
import sys
import time

from . import _samp
from .options import RunFitOptions


def list_sequences(root):
    """Names of the sequence folders directly under root (those with calib/), sorted."""
    names = []
    for name in sorted(os.listdir(root)):
        if os.path.isdir(os.path.join(root, name, "calib")):
            names.append(name)
    return names


def sequences_of_args(args):
    """(name, input path) of every sequence the arguments name, in order: the folders
    under --seq-root, or the sequences of --kitti-tracking / --kitti-stereo (--sequence)
    as samp fit lists them (ROOT/image_02/<seq>, ROOT/calib_cam_to_cam/<seq>.txt)."""
    if args.seq_root:
        names = list_sequences(args.seq_root)
        if not names:
            raise _samp.Error("--seq-root %s holds no sequence folder (a folder with calib/)" % args.seq_root)
        return [(n, os.path.join(args.seq_root, n)) for n in names]
    if args.kitti_tracking:
        paths = _samp.kitti_tracking_sequence_folders(args.kitti_tracking, args.sequence)
    else:
        paths = _samp.kitti_stereo_sequences(args.kitti_stereo, args.sequence)
    if not paths:
        raise _samp.Error("%s holds no sequence" % (args.kitti_tracking or args.kitti_stereo))
    return [(_samp.sequence_output_name(p), p) for p in paths]


def fit_task(options_json, seq_dir, out_dir):
    """One sequence on a worker: RunFit into out_dir. Returns a plain dict (never raises:
    a samp.Error is a failed sequence, reported by the client)."""
    start = time.time()
    start_cpu = time.thread_time()
    result = {"sequence": seq_dir, "output": out_dir, "host": os.uname().nodename, "pid": os.getpid()}
    try:
        native = _samp.RunFitOptions()
        tree = json.loads(options_json)
        tree["sequences"] = [seq_dir]
        tree["output_dir"] = out_dir
        native.from_json(json.dumps(tree))
        summary = _samp.run_fit(native)
        result["failure"] = summary["failure"]
        result["report"] = summary["report"]
        result["num_tracks_fitted"] = summary["num_tracks_fitted"]
        result["num_tracks_failed"] = summary["num_tracks_failed"]
    except _samp.Error as e:
        result["failure"] = str(e)
        result["report"] = ""
        result["num_tracks_fitted"] = 0
        result["num_tracks_failed"] = 0
    result["seconds"] = time.time() - start
    result["cpu_seconds"] = time.thread_time() - start_cpu
    return result


def _parse_set(text):
    if "=" not in text:
        raise ValueError("--set %r: expected FIELD=VALUE (e.g. fit.em_iterations=2)" % text)
    key, value = text.split("=", 1)
    try:
        parsed = json.loads(value)
    except json.JSONDecodeError:
        parsed = value  # a bare string, e.g. fit.data_term=paper
    return key.split("."), parsed


def fit_options_from_args(args):
    """The RunFitOptions of the run: config.json of an earlier fit (--config), then the
    flags, then each --set, validated by Check()."""
    options = RunFitOptions()
    if args.config:
        with open(args.config) as f:
            config = json.load(f)
        for key in ("fit", "sequence", "num_threads", "write_meshes", "link_only", "model",
                    "self_calibrate", "detector_model", "detector_plot", "calibration"):
            if key in config:
                options.from_dict({key: config[key]})
    if args.model:
        options.model = args.model
    if args.threads is not None:
        options.num_threads = args.threads
    if args.no_meshes:
        options.write_meshes = False
    if args.single_frame:
        options.fit.single_frame = True
    if args.link_only:
        options.link_only = True
    if args.frames:
        options.sequence.first_frame, options.sequence.last_frame = _samp.parse_frame_range(args.frames)
    if args.detections:
        options.sequence.detections = os.path.abspath(args.detections)
    if args.detection_format:
        options.sequence.detection_format = args.detection_format
    if args.no_detector_plot:
        options.detector_plot = False
    if args.min_score is not None:
        options.sequence.min_detection_score = args.min_score
    if args.types:
        options.sequence.object_types = [t for t in args.types.split(",") if t]
    for item in args.set or []:
        path, value = _parse_set(item)
        options._set(tuple(path), value)
    # Placeholders for Check(); each task sets its own.
    options.sequences = ["-"]
    options.output_dir = "-"
    options.check()
    return options


# glibc malloc settings of the LocalCluster's worker processes. Dask's default
# (distributed.nanny.pre-spawn-environ: MALLOC_TRIM_THRESHOLD_=65536) returns
# every freed block above 64 KB to the kernel, and setting it also fixes the
# mmap threshold at 128 KB: each model's and each sequence's large transient
# buffers then come back as fresh pages, faulted in and zeroed one by one. On
# the 2-core machine that made a training task 0.31 s against 0.25 s with
# these values (docs/benchmarks.md, "samp.batch"). Variables already in the
# environment take precedence (Dask's rule); docs/cluster.md says the same
# for remote workers.
WORKER_MALLOC_ENVIRON = {"MALLOC_TRIM_THRESHOLD_": str(64 << 20), "MALLOC_MMAP_THRESHOLD_": str(32 << 20)}


# Dask's housekeeping in the LocalCluster's processes, slowed down. Every
# worker samples its task thread's Python stack every 10 ms for the dashboard's
# profile (there is no dashboard here; samp's tasks are native code), and
# every process checks its event loop every 20 ms, its memory every 100 ms and
# its system load every 500 ms; the scheduler looks for work to steal every
# 100 ms. Once every core runs a task, that CPU comes out of the tasks' time;
# these values halve it (the figures: docs/benchmarks.md, "Python package and
# samp.batch"). Stealing is not needed:
# the tasks are independent and the scheduler queues them (worker-saturation),
# handing each worker a new one as it finishes.
LOCAL_CLUSTER_CONFIG = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "200ms",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.scheduler.work-stealing": False,
}


def _client(args):
    import dask
    from distributed import Client, LocalCluster

    if args.scheduler == "local":
        settings = {"distributed.nanny.pre-spawn-environ." + k: v for k, v in WORKER_MALLOC_ENVIRON.items()}
        settings.update(LOCAL_CLUSTER_CONFIG)
        with dask.config.set(settings):
            cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
        return Client(cluster), cluster
    return Client(args.scheduler, timeout=args.connect_timeout), None


def _progress_line(done, total, failed, start):
    width = 30
    filled = int(width * done / total) if total else width
    return "\r[%s%s] %d/%d sequences, %d failed, %.0f s" % (
        "#" * filled, "." * (width - filled), done, total, failed, time.time() - start)


def _remove_dead_staging(out_root, names):
    """Removes the staging folders (".tmp.<pid>.<n>.<name>", core/atomic_file.h)
    of this batch's sequences that a killed worker left in OUT. Called when every
    task has finished, so no live writer owns one; other folders are not touched."""
    import re
    import shutil
    pattern = re.compile(r"^\.tmp\.\d+\.\d+\.(.+)$")
    wanted = set(names)
    for entry in os.listdir(out_root):
        m = pattern.match(entry)
        if m and m.group(1) in wanted:
            shutil.rmtree(os.path.join(out_root, entry), ignore_errors=True)


def run_fit_batch(args, out=sys.stdout, err=sys.stderr):
    from distributed import as_completed

    options = fit_options_from_args(args)
    sequences = sequences_of_args(args)
    names = [n for n, _ in sequences]
    inputs = dict(sequences)
    if len(inputs) != len(names):
        raise _samp.Error("two sequences share a name (%s): their outputs would collide in OUT" %
                          ", ".join(sorted(set(n for n in names if names.count(n) > 1))))
    if args.detections and len(names) > 1 and not os.path.isdir(args.detections):
        raise _samp.Error("--detections %s is a file, but %d sequences are fitted: give a folder with "
                          "<seq>.txt per sequence" % (args.detections, len(names)))
    os.makedirs(args.out, exist_ok=True)
    options_json = options.native.to_json()
    client, cluster = _client(args)
    start = time.time()
    results = {}
    try:
        futures = {}
        for name in names:
            seq_dir = inputs[name]
            out_dir = os.path.join(args.out, name)
            future = client.submit(fit_task, options_json, seq_dir, out_dir, key="samp-fit-" + name + "-" +
                                   str(abs(hash((args.out, start)))), pure=False, retries=args.retries)
            futures[future] = name
        failed = 0
        for future in as_completed(list(futures)):
            name = futures[future]
            try:
                r = future.result()
            except Exception as e:  # the task could not run at all (e.g. samp not importable on a worker)
                r = {"sequence": inputs[name], "failure": "task failed: %s" % e,
                     "report": "", "num_tracks_fitted": 0, "num_tracks_failed": 0}
            results[name] = r
            failed += bool(r["failure"])
            if args.progress:
                err.write(_progress_line(len(results), len(names), failed, start))
                err.flush()
        if args.progress:
            err.write("\n")
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    _remove_dead_staging(args.out, names)
    failures = [(n, results[n]["failure"]) for n in names if results[n]["failure"]]
    fitted = sum(results[n]["num_tracks_fitted"] for n in names)
    out.write("%d sequence(s) (%d failed), %d track(s) fitted, %.1f s\n" % (
        len(names), len(failures), fitted, time.time() - start))
    if args.summary_file:
        with open(os.path.join(args.out, "batch_summary.json"), "w") as f:
            json.dump({"sequences": [results[n] for n in names]}, f, indent=2)
    for name, why in failures:
        out.write("  FAILED %s: %s\n" % (name, why))
    out.write("wrote %s\n" % args.out)
    return 1 if failures else 0


# ---------------------------------------------------------------------- train
#
# SDFs on the workers, PCA on the client from a streamed Gram accumulation:
# each model's SDF (TrainJobSdf, as samp train computes it) stays in its
# worker's memory; blocks of B grids are stacked there, and the client only
# receives reductions: the running double sum for the mean (a chain of tasks
# over the blocks in order), the blocks of the centred Gram matrix and the
# blocks' products Xc_b P, computed by the library's own kernels
# (model/gram.h CentredGram, CentredProduct). The client holds the N x N Gram
# matrix, the mean (D) and the components (D x R), nothing else that grows
# with N. The PCA follows model/pca.cc step by step (float mean of double
# sums; Gram / (N - 1); top R eigenpairs; W = Xc V diag(1 / sqrt((N - 1)
# lambda)); Cholesky-QR re-orthonormalisation; the largest-magnitude entry of
# each component positive), so the model matches samp train's to round-off
# of the eigensolver (numpy's LAPACK here, Eigen or Spectra there).

_JOBS = {}


def _train_jobs(options_json):
    """The job list of TrainOptions (ListTrainJobs), once per worker process and options."""
    if options_json not in _JOBS:
        native = _samp.TrainOptions()
        native.from_json(options_json)
        _JOBS[options_json] = (native, _samp.list_train_jobs(native))
    return _JOBS[options_json]


def sdf_task(options_json, index):
    """One model's SDF on a worker (TrainJobSdf): a dict with `values` (D float32, empty
    when the model is not usable) and the shape's figures."""
    native, jobs = _train_jobs(options_json)
    result = _samp.train_job_sdf(jobs[index], native)
    result["index"] = index
    result["pid"] = os.getpid()
    return result


def _shape_meta(result):
    return {k: v for k, v in result.items() if k != "values"}


def _stack(*results):
    import numpy as np
    return np.stack([r["values"] for r in results], axis=1)  # D x B float32


def _add_columns(total, x):
    """total + the columns of x, one after the other in double (model/pca.cc's mean)."""
    import numpy as np
    total = np.zeros(x.shape[0]) if total is None else total.copy()
    for k in range(x.shape[1]):
        total += x[:, k].astype(np.float64)
    return total


def _gram_block(xa, xb, mean):
    """The (a, b) block of the centred Gram matrix, by the library's kernel (model/gram.h)."""
    import numpy as np
    if xb is None:
        return _samp.centred_gram(xa, mean)
    both = _samp.centred_gram(np.asfortranarray(np.hstack([xa, xb])), mean)
    return both[:xa.shape[1], xa.shape[1]:].copy()


def _product_block(x, mean, p):
    return _samp.centred_product(x, mean, p)


def train_options_from_args(args):
    from .options import TrainOptions

    options = TrainOptions()
    if args.config:
        with open(args.config) as f:
            options.from_dict(json.load(f))
    options.cad_folder = args.cad_dir
    options.output = args.output
    if args.components is not None:
        options.pca.num_components = args.components
    if args.threads is not None:
        options.num_threads = args.threads
    options.show_progress = False
    for item in args.set or []:
        path, value = _parse_set(item)
        options._set(tuple(path), value)
    options.check()
    return options


def run_train_batch(args, out=sys.stdout, err=sys.stderr):
    import numpy as np
    from distributed import as_completed

    options = train_options_from_args(args)
    options_json = options.native.to_json()
    native, jobs = _train_jobs(options_json)
    num_jobs = len(jobs)
    r = options.pca.num_components
    dim = int(np.prod(options.grid.dims))
    client, cluster = _client(args)
    start = time.time()
    try:
        todo = [i for i in range(num_jobs) if not jobs[i].skip]
        sdfs = {i: client.submit(sdf_task, options_json, i, pure=False) for i in todo}
        metas = {client.submit(_shape_meta, sdfs[i]): i for i in todo}
        shapes = {}
        for i in range(num_jobs):
            if jobs[i].skip:
                shapes[i] = {"name": jobs[i].name, "file": jobs[i].relative_path, "used": False,
                             "reject_reason": "skipped by the manifest: " + jobs[i].skip_reason, "seconds": 0.0}
        rejected = 0
        for future in as_completed(list(metas)):
            meta = future.result()
            shapes[meta["index"]] = meta
            rejected += not meta["used"]
            if args.progress:
                err.write("\r[%d/%d] SDFs, %d rejected, %.0f s" % (len(shapes), num_jobs, rejected, time.time() - start))
                err.flush()
        if args.progress:
            err.write("\n")
        for i in range(num_jobs):
            if not shapes[i]["used"]:
                err.write("skipping %s: %s\n" % (shapes[i]["file"], shapes[i]["reject_reason"]))
        used = [i for i in range(num_jobs) if shapes[i]["used"]]
        for i in todo:
            if not shapes[i]["used"]:
                sdfs.pop(i).release()
        n = len(used)
        if n < r + 1:
            raise _samp.Error("only %d of %d models are usable; a model with R = %d components needs at least %d "
                              "(see the 'skipping' lines above for the reasons)" % (n, num_jobs, r, r + 1))
        block = args.block
        blocks = [used[b:b + block] for b in range(0, n, block)]
        offsets = np.cumsum([0] + [len(b) for b in blocks])
        stacks = [client.submit(_stack, *[sdfs[i] for i in b], pure=False) for b in blocks]
        # Mean: double sums over the grids in order, rounded to float (model/pca.cc),
        # accumulated along a chain of tasks, one block after the other.
        total = None
        for stack in stacks:
            total = client.submit(_add_columns, total, stack, pure=False)
        mean32 = (total.result() / n).astype(np.float32)
        mean_future = client.scatter(mean32, broadcast=True)
        # The centred Gram matrix, streamed block by block as the blocks arrive.
        gram = np.zeros((n, n))
        pending = {}
        for a in range(len(blocks)):
            for b in range(a, len(blocks)):
                f = client.submit(_gram_block, stacks[a], stacks[b] if b != a else None, mean_future, pure=False)
                pending[f] = (a, b)
        for f in as_completed(list(pending)):
            a, b = pending.pop(f)
            value = f.result()
            gram[offsets[a]:offsets[a + 1], offsets[b]:offsets[b + 1]] = value
            gram[offsets[b]:offsets[b + 1], offsets[a]:offsets[a + 1]] = value.T
            del value
        gram /= n - 1
        total_variance = float(np.trace(gram))
        eigenvalues, eigenvectors = np.linalg.eigh(gram)
        del gram
        eigenvalues = eigenvalues[::-1][:r].copy()
        eigenvectors = eigenvectors[:, ::-1][:, :r].copy()
        tiny = 1e-7 * max(total_variance, 1e-300)
        for k in range(r):
            if not (np.isfinite(eigenvalues[k]) and eigenvalues[k] > tiny):
                raise _samp.Error("PCA: the samples span only %d independent directions, fewer than the %d "
                                  "components asked for (eigenvalue %d = %g)" % (k, r, k, eigenvalues[k]))
        projection = eigenvectors / np.sqrt(eigenvalues * (n - 1))[None, :]
        components = np.zeros((dim, r))
        products = [client.submit(_product_block, stacks[a], mean_future,
                                  np.asfortranarray(projection[offsets[a]:offsets[a + 1]]), pure=False)
                    for a in range(len(blocks))]
        for f in products:  # in block order: the same double sums in every run
            components += f.result()
        # Cholesky QR (R^T R = W^T W, W <- W R^-1), then the sign rule.
        upper = np.linalg.cholesky(components.T @ components).T
        if np.any(np.diag(upper) <= 0.5):
            raise _samp.Error("PCA: a component degenerated before re-normalisation")
        components = np.linalg.solve(upper.T, components.T).T
        for k in range(r):
            if components[np.argmax(np.abs(components[:, k])), k] < 0:
                components[:, k] *= -1.0
        names = [shapes[i]["name"] for i in used]
        _samp.save_model(native, mean32, components.astype(np.float32), eigenvalues, total_variance, names)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    explained = eigenvalues.sum() / total_variance if total_variance > 0 else 0.0
    sdf_seconds = [shapes[i]["seconds"] for i in used]
    out.write("%d of %d models used, R = %d, explained variance %.4f, %.1f s (SDF %.3f s per model on a worker)\n"
              % (n, num_jobs, r, explained, time.time() - start, float(np.mean(sdf_seconds))))
    out.write("wrote %s\n" % args.output)
    return 0


def build_parser():
    parser = argparse.ArgumentParser(prog="python3 -m samp.batch", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    fit = sub.add_parser("fit", help="fit every sequence of a dataset, one `samp fit` output per sequence")
    fit.add_argument("--scheduler", required=True,
                     help="Dask scheduler address (tcp://HOST:8786) or 'local' (a LocalCluster on this machine)")
    fit.add_argument("--workers", type=int, default=2, help="workers of --scheduler local (processes)")
    source = fit.add_mutually_exclusive_group(required=True)
    source.add_argument("--seq-root", help="folder of sequence folders in samp's layout (each as for samp fit --seq)")
    source.add_argument("--kitti-tracking", metavar="ROOT",
                        help="KITTI tracking folder in its own layout (training/ or testing/), as samp fit's")
    source.add_argument("--kitti-stereo", metavar="ROOT",
                        help="KITTI stereo 2015 multiview folder in its own layout, as samp fit's")
    fit.add_argument("--sequence", default="all",
                     help="with --kitti-tracking / --kitti-stereo: sequences, comma-separated, or all (default)")
    fit.add_argument("--frames", help="fit only frames FIRST-LAST (e.g. 100-300) of each sequence")
    fit.add_argument("--detections", help="as samp fit --detections: a file (one sequence) or a folder "
                                          "with <seq>.txt per sequence")
    fit.add_argument("--detection-format", choices=["auto", "kitti-object", "kitti-tracking", "ab3dmot"],
                     help="as samp fit --detection-format")
    fit.add_argument("--min-score", type=float, help="as samp fit --min-score")
    fit.add_argument("--types", help="as samp fit --types (comma-separated, default Car)")
    fit.add_argument("--out", required=True, help="output folder: OUT/NAME per sequence NAME")
    fit.add_argument("--model", help="shape model file (.vdb); required unless --config names one")
    fit.add_argument("--config", help="config.json of an earlier samp fit: its fit/sequence options")
    fit.add_argument("--threads", type=int, help="RunFitOptions.num_threads per task (0 = all cores; "
                                                  "default 0, as samp fit)")
    fit.add_argument("--no-meshes", action="store_true", help="as samp fit --no-meshes")
    fit.add_argument("--single-frame", action="store_true", help="as samp fit --single-frame")
    fit.add_argument("--link-only", action="store_true", help="as samp fit --link-only")
    fit.add_argument("--no-detector-plot", action="store_true", help="as samp fit --no-detector-plot")
    fit.add_argument("--set", action="append", metavar="FIELD=VALUE",
                     help="any RunFitOptions field by its config.json path, value as JSON "
                          "(fit.em_iterations=2, sequence.tracker.min_track_length=1); repeatable")
    fit.add_argument("--retries", type=int, default=0,
                     help="extra attempts of a task that raised (a dead worker's tasks are rescheduled "
                          "by the scheduler regardless)")
    fit.add_argument("--connect-timeout", default="30s", help="timeout to reach the scheduler")
    fit.add_argument("--no-progress", dest="progress", action="store_false", help="no progress bar")
    fit.add_argument("--summary-file", action="store_true",
                     help="also write OUT/batch_summary.json (per sequence: worker, seconds, failure)")
    train = sub.add_parser("train", help="train a shape model: SDFs on the workers, PCA on the client")
    train.add_argument("cad_dir", help="CAD folder (as samp train's)")
    train.add_argument("-o", "--output", required=True, help="model file (.vdb) to write")
    train.add_argument("--scheduler", required=True, help="Dask scheduler address or 'local'")
    train.add_argument("--workers", type=int, default=2, help="workers of --scheduler local (processes)")
    train.add_argument("--components", type=int, help="PcaOptions.num_components (R)")
    train.add_argument("--threads", type=int, help="TrainOptions.num_threads per SDF task (0 = all cores)")
    train.add_argument("--config", help="JSON of TrainOptions fields (samp.TrainOptions().to_dict() keys)")
    train.add_argument("--set", action="append", metavar="FIELD=VALUE",
                       help="any TrainOptions field by its path, value as JSON (scan.num_views=50); repeatable")
    train.add_argument("--block", type=int, default=512,
                       help="grids per block task (512 = the Gram kernel's summation depth: the same sums as samp train)")
    train.add_argument("--connect-timeout", default="30s", help="timeout to reach the scheduler")
    train.add_argument("--no-progress", dest="progress", action="store_false", help="no progress line")
    return parser


def main(argv=None):
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        if args.command == "fit":
            if not args.model and not args.config:
                parser.error("fit: give --model (or --config naming one)")
            if args.seq_root and args.sequence != "all":
                parser.error("fit: --sequence names sequences of --kitti-tracking or --kitti-stereo")
            return run_fit_batch(args)
        if args.command == "train":
            return run_train_batch(args)
    except (_samp.Error, ValueError, TypeError, AttributeError, OSError) as e:
        sys.stderr.write("samp.batch: error: %s\n" % e)
        return 1
    return 2


if __name__ == "__main__":
    # Run from the module samp.batch (not __main__), so that the tasks are
    # pickled by reference and the workers import them from the package.
    from samp.batch import main as _main

    sys.exit(_main())
