"""The Python API of samp (libsamp/python): models, options, fit_sequence, train, sdf_of_mesh."""

import json
import os
import shutil
import subprocess
import threading

import numpy as np
import pytest

import samp
from conftest import assert_same_files, require_kitti, shipped_model, tree_bytes, without_timings


@pytest.fixture(scope="module")
def model():
    return samp.ShapeModel.load(shipped_model())


# ------------------------------------------------------------------ ShapeModel

def test_model_arrays_have_the_grid_shape(model):
    dims = tuple(int(d) for d in model.grid["dims"])
    r = model.num_components
    assert r >= 1
    assert model.mean.shape == dims and model.mean.dtype == np.float32
    assert model.components.shape == dims + (r,)
    assert model.eigenvalues.shape == (r,)
    assert np.all(np.diff(model.eigenvalues) <= 0) and np.all(model.eigenvalues > 0)
    # Orthonormal columns (D x R).
    w = model.components.reshape(-1, r, order="F").astype(np.float64)
    np.testing.assert_allclose(w.T @ w, np.eye(r), atol=1e-4)
    assert len(model.training_shapes) > r
    assert "pca" in model.train_options


def test_sdf_is_mean_plus_components(model):
    r = model.num_components
    np.testing.assert_array_equal(model.sdf(np.zeros(r)), model.mean)
    z = np.linspace(-1.0, 1.0, r) * np.sqrt(model.eigenvalues)
    expected = model.mean.astype(np.float64) + np.tensordot(model.components.astype(np.float64), z, axes=([3], [0]))
    np.testing.assert_allclose(model.sdf(z), expected, atol=1e-5)
    # Fortran layout: a[i, j, k] sits at origin + voxel_size * (i, j, k); the grid's
    # far corner is outside the car, the bottom centre region inside.
    g = model.grid
    assert model.mean[0, 0, 0] > 0
    centre = np.round((np.array([0.0, -0.7, 0.0]) - g["origin"]) / g["voxel_size"]).astype(int)
    assert model.mean[tuple(centre)] < 0


def test_encode_recovers_a_code_of_the_manifold(model):
    r = model.num_components
    z = 0.5 * np.sqrt(model.eigenvalues) * np.where(np.arange(r) % 2 == 0, 1.0, -1.0)
    np.testing.assert_allclose(model.encode(model.sdf(z)), z, atol=1e-3 * np.sqrt(model.eigenvalues[0]))
    # Flat values in x-fastest order are the same grid.
    np.testing.assert_allclose(model.encode(model.sdf(z).ravel(order="F")), z,
                               atol=1e-3 * np.sqrt(model.eigenvalues[0]))
    with pytest.raises(samp.Error, match="shape"):
        model.encode(np.zeros((3, 4, 5), np.float32))


def test_mesh_is_a_closed_car_sized_surface(model):
    vertices, faces = model.mesh(np.zeros(model.num_components))
    assert vertices.shape[1] == 3 and faces.shape[1] == 3 and len(faces) > 100
    assert faces.min() >= 0 and faces.max() < len(vertices)
    extent = vertices.max(axis=0) - vertices.min(axis=0)
    assert 3.0 < extent[0] < 6.0  # length along x
    assert 1.0 < extent[1] < 2.5  # height along y
    with pytest.raises(samp.Error, match="components"):
        model.mesh(np.zeros(model.num_components + 1))


def test_load_error_is_samp_error_with_the_cli_message(tmp_path):
    missing = str(tmp_path / "missing.vdb")
    with pytest.raises(samp.Error) as info:
        samp.ShapeModel.load(missing)
    assert missing in str(info.value)
    assert isinstance(info.value, RuntimeError)
    # The same message as the samp CLI prints for the same call (RunFit loads the model).
    seq = require_kitti()
    cli = subprocess.run([os.environ["SAMP_EXECUTABLE"], "fit", "--model", missing, "--seq", seq,
                          "--out", str(tmp_path / "cli")], capture_output=True, text=True)
    assert cli.returncode != 0
    with pytest.raises(samp.Error) as fit_info:
        samp.fit_sequence(seq, missing)
    assert cli.stderr.strip().splitlines()[-1] == "samp: error: " + str(fit_info.value)


# ------------------------------------------------------------------ options

def test_options_are_the_structs_fields():
    o = samp.RunFitOptions()
    assert o.write_meshes is True and o.num_threads == 0
    assert isinstance(o.fit.em_iterations, int)
    o.fit.em_iterations = 3
    o.fit.motion_noise.sigma_yaw = 0.25
    o.sequence.tracker.min_track_length = 1
    assert o.fit.em_iterations == 3
    assert o.fit.motion_noise.sigma_yaw == 0.25
    assert o.to_dict()["sequence"]["tracker"]["min_track_length"] == 1
    # The same field table as config.json: the struct round-trips through JSON.
    copy = samp.RunFitOptions().from_dict(o.to_dict())
    assert copy == o
    f = samp.FitOptions(single_frame=True, em_iterations=0)
    assert f.single_frame and f.em_iterations == 0
    assert f.data_term in ("paper", "ray_depth", "ray-depth") or isinstance(f.data_term, str)


def test_options_list_the_fields_that_config_json_omits_at_their_default():
    # config.json holds some fields only when they differ from their default;
    # the options objects list and set them all the same.
    o = samp.RunFitOptions()
    tree = o.to_dict()
    assert tree["detector_plot"] is True and tree["self_calibrate"] is True and tree["detector_model"] == ""
    assert "detections" in tree["sequence"]
    o.detector_plot = False
    o.sequence.detections = "dets"
    assert o.detector_plot is False and o.sequence.detections == "dets"
    assert samp.RunFitOptions().from_dict(o.to_dict()) == o


def test_batch_options_take_the_optional_fields_from_flags_and_config(tmp_path):
    from samp import batch
    parser = batch.build_parser()
    args = parser.parse_args(["fit", "--scheduler", "local", "--seq-root", str(tmp_path), "--out", str(tmp_path / "o"),
                              "--model", "m.vdb", "--no-detector-plot", "--detections", "dets"])
    o = batch.fit_options_from_args(args)
    assert o.detector_plot is False
    assert o.sequence.detections == os.path.abspath("dets")
    config = tmp_path / "config.json"
    config.write_text(json.dumps({"detector_plot": False, "self_calibrate": False, "fit": {"em_iterations": 2}}))
    args = parser.parse_args(["fit", "--scheduler", "local", "--seq-root", str(tmp_path), "--out", str(tmp_path / "o"),
                              "--model", "m.vdb", "--config", str(config)])
    o = batch.fit_options_from_args(args)
    assert o.detector_plot is False and o.self_calibrate is False and o.fit.em_iterations == 2


def test_options_refuse_unknown_fields_and_wrong_types():
    o = samp.RunFitOptions()
    with pytest.raises(AttributeError, match="fit.no_such_field"):
        o.fit.no_such_field = 1
    with pytest.raises(AttributeError):
        o.nothing
    with pytest.raises(TypeError, match="em_iterations"):
        o.fit.em_iterations = 1.5
    with pytest.raises(TypeError, match="write_meshes"):
        o.write_meshes = 1
    # An enum by name: an unknown name is the library's error, naming the key.
    with pytest.raises(samp.Error, match="data_term"):
        o.fit.data_term = "no-such-term"


def test_check_is_the_structs_check():
    o = samp.FitOptions()
    o.check()
    o.em_iterations = -1
    with pytest.raises(samp.Error, match=r"^FitOptions.em_iterations must be >= 0, got -1"):
        o.check()
    r = samp.RunFitOptions()
    with pytest.raises(samp.Error, match=r"^RunFitOptions.model must be given unless link_only"):
        r.check()
    t = samp.TrainOptions(cad_folder="cad", output="model.vdb")
    t.check()
    t.pca.num_components = 0
    with pytest.raises(samp.Error, match="num_components"):
        t.check()


def test_options_pickle():
    import pickle
    o = samp.RunFitOptions()
    o.fit.em_iterations = 4
    assert pickle.loads(pickle.dumps(o)) == o


# ------------------------------------------------------------------ fit_sequence

def test_fit_sequence_on_the_real_kitti_frame(model):
    seq = require_kitti()
    result = samp.fit_sequence(seq, model)
    assert result.ok, result.failure
    assert len(result.tracks) == 1
    track = result.tracks[0]
    assert track.shape_code.shape == (model.num_components,)
    assert list(track.frames) == [10]
    assert track.position_world.shape == (1, 3)
    assert track.num_points[0] > 500
    assert np.isfinite(track.yaw).all()
    # ~13 m in front of the camera (the detection), on the road.
    assert 8.0 < np.linalg.norm(track.position_world[0]) < 20.0
    # A car the model spans: its shape inside the grid, no flag in tracks.json.
    assert track.at_grid_limit == [] and "at_grid_limit" not in track.record
    assert result.summary["sequences"][0]["num_at_grid_limit"] == 0
    assert result.sequences[0]["ok"] and result.sequences[0]["tracking"]["detections"] == 1
    assert result.summary["num_tracks_fitted"] == 1
    # The run's detector model (self-calibration on one detection: the defaults,
    # with notes) in tracks.json, as detector_model.json and the summary hold it.
    assert result.detector_model["origin"] == "self-calibration"
    with open(os.path.join(result.folder, "detector_model.json")) as f:
        assert result.detector_model["model"] == json.load(f)
    assert result.summary["detector_model"] == result.detector_model["model"]
    assert result.detector_model["model"]["source"] == "defaults"
    assert result.detector_model["model"]["samples"]["frames"] == 1
    assert result.detector_model["model"]["notes"]
    # Its plot beside it (as samp fit draws it), unless detector_plot is off.
    assert "detector_model.png" in result.files()
    with open(os.path.join(result.folder, "detector_model.png"), "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    assert "detector_plot" not in result.config
    # The sequence's stages: reading the frames and the fit took time, no stage
    # is negative, and together they are no more than the whole sequence.
    seq_summary = result.summary["sequences"][0]
    stages = [seq_summary["seconds_" + s] for s in ("frames", "tracking", "fit", "output")]
    assert all(t >= 0.0 for t in stages)
    assert seq_summary["seconds_frames"] > 0.0 and seq_summary["seconds_fit"] > 0.0
    assert sum(stages) <= seq_summary["seconds"] + 1e-6
    vertices, faces = result.read_mesh(track)
    assert len(faces) > 100
    assert "label_02/000046.txt" in result.files()


def test_fit_result_write_is_byte_identical_to_samp_fit(model, tmp_path):
    seq = require_kitti()
    options = samp.RunFitOptions()
    options.num_threads = 1
    options.fit.em_iterations = 1
    result = samp.fit_sequence(seq, model, options)
    out = str(tmp_path / "out")
    result.write(out)
    python_files = tree_bytes(out)
    shutil.move(out, str(tmp_path / "python"))
    cli = subprocess.run([os.environ["SAMP_EXECUTABLE"], "fit", "--model", model.path, "--seq", seq,
                          "--out", out, "--threads", "1", "--em-iterations", "1"],
                         capture_output=True, text=True)
    assert cli.returncode == 0, cli.stderr
    cli_files = tree_bytes(out)
    assert_same_files(python_files, cli_files)
    # The comparison sees a change of a fitted value (and leaves the timings alone only).
    tampered = python_files["tracks.json"].replace(b'"yaw": ', b'"yaw": 1', 1)
    assert without_timings("tracks.json", tampered) != without_timings("tracks.json", cli_files["tracks.json"])
    # write() replaces an earlier samp fit output, refuses any other folder.
    result.write(out)
    other = tmp_path / "other"
    other.mkdir()
    (other / "keep.txt").write_text("x")
    with pytest.raises(samp.Error, match="not the output of a samp fit"):
        result.write(str(other))


def test_fit_sequence_failure_is_reported_like_samp_fit(model, tmp_path):
    empty = tmp_path / "not_a_sequence"
    empty.mkdir()
    result = samp.fit_sequence(str(empty), model)
    assert not result.ok
    assert result.failure == "every sequence failed"
    assert not result.sequences[0]["ok"] and result.sequences[0]["error"]


def test_native_calls_release_the_gil(model, tmp_path):
    # While RunFit runs in one thread, another keeps running Python code: its
    # ticks cover the native call with no gap as long as the call (holding the
    # GIL would stop the ticker for the whole call).
    import json
    import time

    from samp import _samp
    seq = require_kitti()
    native = _samp.RunFitOptions()
    tree = json.loads(native.to_json())
    tree.update(model=model.path, sequences=[seq], output_dir=str(tmp_path / "out"), num_threads=1)
    native.from_json(json.dumps(tree))
    ticks = []
    done = threading.Event()

    def ticker():
        while not done.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.001)

    t = threading.Thread(target=ticker)
    t.start()
    time.sleep(0.05)
    start = time.monotonic()
    summary = _samp.run_fit(native)
    end = time.monotonic()
    done.set()
    t.join()
    assert summary["num_tracks_fitted"] == 1
    inside = [start] + [x for x in ticks if start < x < end] + [end]
    assert max(np.diff(inside)) < 0.5 * (end - start), (len(inside), end - start)


# ------------------------------------------------------------------ sdf_of_mesh, train

def write_box_obj(path, length, height, width):
    """A closed box car body (OBJ, y up, x forward), bottom at y = 0."""
    l, h, w = length / 2, height, width / 2
    v = [(x, y, z) for x in (-l, l) for y in (0.0, h) for z in (-w, w)]
    faces = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
    with open(path, "w") as f:
        for p in v:
            f.write("v %g %g %g\n" % p)
        for q in faces:
            f.write("f %d %d %d\nf %d %d %d\n" % (q[0], q[1], q[2], q[0], q[2], q[3]))


def small_train_options():
    o = samp.TrainOptions()
    o.scan.num_views = 24
    o.scan.width = 96
    o.scan.height = 96
    o.grid.voxel_size = 0.2
    o.grid.dims = [31, 15, 15]
    o.grid.origin = [-3.0, -2.3, -1.4]
    o.num_threads = 1
    o.show_progress = False
    return o


def test_sdf_of_mesh_of_a_box(tmp_path):
    path = str(tmp_path / "box.obj")
    write_box_obj(path, 4.2, 1.5, 1.8)
    o = small_train_options()
    result = samp.sdf_of_mesh(path, o)
    values = result["values"]
    assert values.shape == (31, 15, 15)
    assert result["sign_ok"]
    np.testing.assert_allclose(result["size"], [4.2, 1.5, 1.8], atol=1e-6)
    g = result["grid"]

    def at(p):
        return values[tuple(np.round((np.asarray(p) - g["origin"]) / g["voxel_size"]).astype(int))]

    # Object frame: y points down, the bottom centre is the origin.
    assert at([0.0, -0.6, 0.0]) < -0.5  # inside, ~0.75 m from the nearest face
    assert at([-3.0, -2.3, -1.4]) > 0.5  # the grid's corner is outside
    with pytest.raises(samp.Error, match="missing.obj"):
        samp.sdf_of_mesh(str(tmp_path / "missing.obj"), o)
    # The file's manifest entry canonicalises it, as in training: the box in
    # centimetres, scaled to a 4.5 m length.
    cad = tmp_path / "cad"
    (cad / "sub").mkdir(parents=True)
    write_box_obj(str(cad / "sub" / "big.obj"), 420.0, 150.0, 180.0)
    manifest = tmp_path / "manifest.json"
    manifest.write_text('{"models": [{"file": "sub/big.obj", "target_length": 4.5, "up": "+y", "forward": "+x"},'
                        ' {"file": "sub/skipped.obj", "skip": true, "skip_reason": "a test"}]}')
    o.manifest = str(manifest)
    o.cad_folder = str(cad)
    scaled = samp.sdf_of_mesh(str(cad / "sub" / "big.obj"), o)
    assert scaled["sign_ok"]
    np.testing.assert_allclose(scaled["size"], [4.5, 150.0 * 4.5 / 420.0, 180.0 * 4.5 / 420.0], rtol=1e-6)
    write_box_obj(str(cad / "sub" / "skipped.obj"), 4.2, 1.5, 1.8)
    with pytest.raises(samp.Error, match="skipped by the manifest .*: a test"):
        samp.sdf_of_mesh(str(cad / "sub" / "skipped.obj"), o)


def test_train_on_boxes(tmp_path):
    cad = tmp_path / "cad"
    cad.mkdir()
    for i, (l, h, w) in enumerate([(3.8, 1.4, 1.7), (4.2, 1.5, 1.8), (4.6, 1.6, 1.8), (5.0, 1.8, 1.9)]):
        write_box_obj(str(cad / ("box%d.obj" % i)), l, h, w)
    o = small_train_options()
    o.pca.num_components = 2
    output = str(tmp_path / "boxes.vdb")
    summary = samp.train(str(cad), output, o)
    assert summary["num_used"] == 4, summary["report"]
    trained = samp.ShapeModel.load(output)
    assert trained.num_components == 2
    assert trained.mean.shape == (31, 15, 15)
    assert sorted(trained.training_shapes) == ["box0", "box1", "box2", "box3"]
    np.testing.assert_allclose(trained.eigenvalues, summary["eigenvalues"])
    # The effective options are stored in the model file.
    assert trained.train_options["scan"]["num_views"] == 24
