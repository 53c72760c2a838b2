"""The library calls of samp from Python (docs/python.md).

Everything that computes is the C++ library (`_samp`): fit_sequence runs
RunFit (pipeline/run_fit.h), the one function behind `samp fit`, so a
FitResult's files are the files `samp fit` writes; train runs
TrainShapeModel (`samp train`); sdf_of_mesh the trainer's CanonicalCad +
ScanToSdf. The GIL is released during the native work, so Python threads run
beside it.
"""

import json
import os
import tempfile

import numpy as np

from . import _samp
from .options import RunFitOptions, TrainOptions

__all__ = ["Error", "ShapeModel", "FitResult", "Track", "fit_sequence", "train", "sdf_of_mesh"]

Error = _samp.Error


class ShapeModel:
    """A shape manifold phi(z) = W z + mu (model/shape_model.h), loaded from its .vdb file.

    Grids are NumPy arrays of shape (nx, ny, nz): a[i, j, k] is the value at
    grid["origin"] + grid["voxel_size"] * (i, j, k) in the object frame (metres).
    """

    def __init__(self, native, path):
        self._native = native
        self.path = path

    @classmethod
    def load(cls, path):
        """Loads and validates a model file; samp.Error names the file and what is wrong."""
        return cls(_samp.ShapeModel.load(os.fspath(path)), os.fspath(path))

    @property
    def num_components(self):
        return self._native.num_components

    @property
    def grid(self):
        """{"origin": (3,), "voxel_size": float, "dims": (3,) int}."""
        return self._native.grid

    @property
    def mean(self):
        """Mean SDF mu, (nx, ny, nz) float32."""
        return self._native.mean

    @property
    def components(self):
        """Principal directions W, (nx, ny, nz, R) float32 (orthonormal as D x R)."""
        return self._native.components

    @property
    def eigenvalues(self):
        """Variances sigma_i^2 of the R components, (R,) float64."""
        return self._native.eigenvalues

    @property
    def total_variance(self):
        return self._native.total_variance

    @property
    def training_shapes(self):
        return self._native.training_shapes

    @property
    def train_options(self):
        """The trainer options stored in the file (dict)."""
        return json.loads(self._native.options_json)

    def sdf(self, z):
        """Dense SDF W z + mu of code z (R values), (nx, ny, nz) float32."""
        return self._native.sdf(np.asarray(z, dtype=np.float64))

    def mesh(self, z, isovalue=0.0):
        """Zero level set of phi_z: (vertices (V, 3) float32, faces (F, 3) int32), object frame."""
        return self._native.mesh(np.asarray(z, dtype=np.float64), isovalue)

    def encode(self, sdf, prior_weight=0.0):
        """Code z of a dense SDF on the model's grid ((nx, ny, nz) or D flat values, x fastest)."""
        return self._native.encode(np.asarray(sdf), prior_weight)

    def __repr__(self):
        g = self.grid
        return "ShapeModel(%r, R=%d, dims=%s, voxel_size=%g)" % (
            self.path, self.num_components, tuple(int(d) for d in g["dims"]), g["voxel_size"])


class Track:
    """One fitted track of a FitResult: the record of tracks.json with arrays.

    track_id, sequence, type, mode ("joint" or "single_frame"), shape_code (R,),
    box_min / box_max (3,) of the fitted shape (None when it has no inside),
    at_grid_limit (the axes, "length" / "height" / "width", along which the
    shape fills the model's grid: an unreliable fit; [] when none),
    mesh / points (paths relative to the output, "" without meshes), summary
    (the fit's costs and solves, a dict), and per frame, as arrays of length F:
    frames (int), time, position_world (F, 3), yaw, speed, yaw_rate,
    num_points, data_cost, motion_model (list of str), ... (every per-frame
    key of tracks.json).
    """

    def __init__(self, record, mesh="", points=""):
        self.record = record
        self.track_id = record["track_id"]
        self.sequence = record.get("sequence", "")
        self.type = record.get("type", "Car")
        self.mode = record.get("mode", "")
        self.shape_code = np.asarray(record["shape_code"], dtype=np.float64)
        self.box_min = np.asarray(record["box_min"]) if "box_min" in record else None
        self.box_max = np.asarray(record["box_max"]) if "box_max" in record else None
        self.at_grid_limit = list(record.get("at_grid_limit", []))
        self.summary = record.get("summary", {})
        self.mesh = mesh
        self.points = points
        frames = record.get("frames", [])
        self.frame_fields = {}
        keys = []
        for f in frames:
            for k in f:
                if k not in keys:
                    keys.append(k)
        for k in keys:
            values = [f.get(k) for f in frames]
            if all(isinstance(v, str) for v in values):
                self.frame_fields[k] = values
            else:
                try:
                    self.frame_fields[k] = np.asarray(values, dtype=np.float64)
                except (TypeError, ValueError):
                    self.frame_fields[k] = values
        if "frame" in self.frame_fields:
            self.frame_fields["frame"] = self.frame_fields["frame"].astype(np.int64)

    def __getattr__(self, name):
        fields = self.__dict__.get("frame_fields", {})
        if name in fields:
            return fields[name]
        if name == "frames" and "frame" in fields:
            return fields["frame"]
        raise AttributeError("Track has no field '%s'" % name)

    def __len__(self):
        return len(self.record.get("frames", []))

    def __repr__(self):
        return "Track(%s %d, %d frames, mode=%s)" % (self.sequence, self.track_id, len(self), self.mode)


class FitResult:
    """What fit_sequence returns: the tracks, the summary, and the files of the run.

    tracks: list of Track; sequences: per sequence dicts of tracks.json
    (directory, name, ok, error, input, input_messages, tracking = the tracker
    summary, failed_tracks); detector_model: the "detector_model" object of
    tracks.json (origin "self-calibration", "file" or "none"; unless "none"
    the model with its sample counts under "model", as detector_model.json
    holds it; None for a tracks.json without it); summary: RunFit's summary
    (dict: sequences, num_tracks_fitted, num_tracks_failed, failure, report,
    detector_model = the model the run used or None, seconds,
    seconds_calibration; each sequence also the wall time of its stages,
    seconds_frames, seconds_tracking, seconds_fit, seconds_output); config:
    the effective options (config.json); failure: why the run failed as `samp
    fit` would (it then exits 1), "" otherwise.

    write(out_dir) writes exactly the files of `samp fit --seq ... --out OUT_DIR`
    (config.json names OUT_DIR as its output_dir).
    """

    def __init__(self, staging, folder, summary):
        self._staging = staging  # TemporaryDirectory owning `folder`
        self.folder = folder
        self.summary = summary
        self.failure = summary["failure"]
        with open(os.path.join(folder, "tracks.json")) as f:
            self.tracks_file = json.load(f)
        with open(os.path.join(folder, "config.json")) as f:
            self.config = json.load(f)
        self.model = self.tracks_file.get("model", "")
        self.detector_model = self.tracks_file.get("detector_model")
        self.sequences = []
        self.tracks = []
        for seq in self.tracks_file.get("sequences", []):
            self.sequences.append({k: v for k, v in seq.items() if k != "tracks"})
            for t in seq.get("tracks", []):
                self.tracks.append(Track(t, t.get("mesh", ""), t.get("points", "")))

    @property
    def ok(self):
        return not self.failure

    def files(self):
        """Relative paths of every file of the run, sorted."""
        out = []
        for root, _, names in os.walk(self.folder):
            for n in names:
                out.append(os.path.relpath(os.path.join(root, n), self.folder))
        return sorted(out)

    def read_mesh(self, track):
        """The fitted surface of a track as written (vertices, faces), from its PLY."""
        return _read_ply(os.path.join(self.folder, track.mesh))

    def write(self, out_dir):
        """Writes the run's files into out_dir (new, empty or an earlier samp fit output,
        replaced as a whole), as `samp fit --out out_dir` writes them."""
        _samp.write_fit_output(self.folder, os.fspath(out_dir))

    def brief_report(self):
        return self.summary["report"]

    def close(self):
        """Removes the run's temporary files (also done when the result is collected)."""
        if self._staging is not None:
            self._staging.cleanup()
            self._staging = None

    def __repr__(self):
        return "FitResult(%d track(s), %s)" % (len(self.tracks), "ok" if self.ok else "failed: " + self.failure)


def _read_ply(path):
    """Vertices and faces of a binary/ascii little-endian PLY written by samp (core/ply_io.h)."""
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline().decode("ascii").strip()
            header.append(line)
            if line == "end_header":
                break
        body = f.read()
    fmt = next(l.split()[1] for l in header if l.startswith("format"))
    elements = []
    for l in header:
        parts = l.split()
        if parts[0] == "element":
            elements.append([parts[1], int(parts[2]), []])
        elif parts[0] == "property":
            elements[-1][2].append(parts[1:])
    types = {"float": "<f4", "float32": "<f4", "double": "<f8", "uchar": "u1", "uint8": "u1",
             "int": "<i4", "int32": "<i4", "uint": "<u4", "uint32": "<u4"}
    vertices = np.zeros((0, 3), np.float32)
    faces = np.zeros((0, 3), np.int32)
    if fmt != "binary_little_endian":
        raise Error("%s: only binary_little_endian PLY is read here (format %s)" % (path, fmt))
    offset = 0
    for name, count, props in elements:
        if name == "vertex":
            dtype = np.dtype([(p[-1], types[p[0]]) for p in props])
            data = np.frombuffer(body, dtype=dtype, count=count, offset=offset)
            offset += dtype.itemsize * count
            vertices = np.stack([data["x"], data["y"], data["z"]], axis=1).astype(np.float32)
        elif name == "face":
            out = np.zeros((count, 3), np.int32)
            p = props[0]  # list <count type> <index type> vertex_indices
            ctype, itype = np.dtype(types[p[1]]), np.dtype(types[p[2]])
            for i in range(count):
                n = int(np.frombuffer(body, ctype, 1, offset)[0])
                offset += ctype.itemsize
                idx = np.frombuffer(body, itype, n, offset)
                offset += itype.itemsize * n
                out[i] = idx[:3]
            faces = out
    return vertices, faces


def _model_path(model):
    if isinstance(model, ShapeModel):
        return model.path
    return os.fspath(model)


def fit_sequence(seq_dir, model, options=None, tracking_labels=None):
    """Fits every track of one sequence directory (docs/sequence_format.md) with RunFit,
    as `samp fit --seq SEQ_DIR --model MODEL` does.

    model: a ShapeModel or a model file path. options: a RunFitOptions (its
    model, sequences and output_dir are set here); tracking_labels: optional
    KITTI tracking label file giving the tracks (`--tracks`). Raises samp.Error
    for invalid options or an unreadable model; a sequence or track that fails
    is in the result (FitResult.sequences, .failure), as with `samp fit`.
    """
    options = RunFitOptions() if options is None else options
    native = _samp.RunFitOptions()
    native.from_json(options.native.to_json())
    tree = json.loads(native.to_json())
    tree["model"] = _model_path(model) if not tree["link_only"] else tree["model"]
    tree["sequences"] = [os.fspath(seq_dir)]
    tree["tracking_labels"] = [os.fspath(tracking_labels)] if tracking_labels else []
    staging = tempfile.TemporaryDirectory(prefix="samp-fit-")
    folder = os.path.join(staging.name, "out")
    tree["output_dir"] = folder
    native.from_json(json.dumps(tree))
    try:
        summary = _samp.run_fit(native)
    except BaseException:
        staging.cleanup()
        raise
    return FitResult(staging, folder, summary)


def train(cad_dir, output, options=None):
    """Trains a shape model from a folder of CAD files (TrainShapeModel, `samp train`)
    and writes it to `output`; returns the summary (dict). options: a TrainOptions
    (its cad_folder and output are set here)."""
    options = TrainOptions() if options is None else options
    native = _samp.TrainOptions()
    tree = json.loads(options.native.to_json())
    tree["cad_folder"] = os.fspath(cad_dir)
    tree["output"] = os.fspath(output)
    native.from_json(json.dumps(tree))
    return _samp.train(native)


def sdf_of_mesh(path, options=None):
    """The SDF of one CAD file as training computes it: canonicalised (its entry in
    options.manifest, matched by the path relative to options.cad_folder or by name;
    else options.preset, the manifest's defaults or automatic axes), scanned (options.scan) and on options.grid (options.sdf).
    Returns a dict: values (nx, ny, nz) float32, grid, inside_fraction, sign_ok,
    report, scale, size, up, forward, warnings."""
    options = TrainOptions() if options is None else options
    return _samp.sdf_of_mesh(os.fspath(path), options.native)
