"""Options objects: the library's option structs, field by field.

Each class wraps one C++ struct (RunFitOptions, FitOptions, SequenceOptions,
TrainOptions). Its fields are the struct's, under the names of the library's
own field table (the keys of a fit's config.json, of the trainer options in a
model file); nested structs are nested objects:

    o = samp.RunFitOptions()
    o.fit.em_iterations = 2
    o.sequence.tracker.min_track_length = 1
    o.check()                      # the struct's Check(): samp.Error naming the field

Every read and write goes through the native struct, so a value of the wrong
type is refused there (samp.Error naming the key), an unknown field is an
AttributeError, and there are no Python-side defaults to drift from C++.
"""

import json

from . import _samp

__all__ = ["RunFitOptions", "FitOptions", "SequenceOptions", "TrainOptions"]


class _View:
    """A nested struct of an options object (writes go to the owner)."""

    __slots__ = ("_owner", "_path")

    def __init__(self, owner, path):
        object.__setattr__(self, "_owner", owner)
        object.__setattr__(self, "_path", path)

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        return self._owner._get(self._path + (name,))

    def __setattr__(self, name, value):
        self._owner._set(self._path + (name,), value)

    def __dir__(self):
        return list(self._owner._node(self._path).keys())

    def to_dict(self):
        return self._owner._node(self._path)

    def __repr__(self):
        return "%s.%s(%s)" % (type(self._owner).__name__, ".".join(self._path),
                              json.dumps(self.to_dict(), sort_keys=True))


class _Options:
    """Base of the options classes; `_native_type` is the _samp struct."""

    _native_type = None

    def __init__(self, **fields):
        object.__setattr__(self, "_native", self._native_type())
        for name, value in fields.items():
            setattr(self, name, value)

    # -- access by path -------------------------------------------------
    def _tree(self):
        return json.loads(self._native.to_json())

    def _node(self, path):
        node = self._tree()
        for i, key in enumerate(path):
            if not isinstance(node, dict) or key not in node:
                raise AttributeError("%s has no field '%s'" % (type(self).__name__, ".".join(path[:i + 1])))
            node = node[key]
        return node

    def _get(self, path):
        value = self._node(path)
        return _View(self, path) if isinstance(value, dict) else value

    def _set(self, path, value):
        tree = self._tree()
        parent = tree
        for i, key in enumerate(path[:-1]):
            if not isinstance(parent.get(key), dict):
                raise AttributeError("%s has no field '%s'" % (type(self).__name__, ".".join(path[:i + 1])))
            parent = parent[key]
        name = ".".join(path)
        key = path[-1]
        if key not in parent:
            raise AttributeError("%s has no field '%s'" % (type(self).__name__, name))
        parent[key] = _checked(name, parent[key], value)
        self._native.from_json(json.dumps(tree))

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        return self._get((name,))

    def __setattr__(self, name, value):
        self._set((name,), value)

    def __dir__(self):
        return list(self._tree().keys()) + ["check", "to_dict", "from_dict", "native"]

    # -- whole-struct operations ------------------------------------------
    def check(self):
        """The struct's Check(): raises samp.Error naming the field and the rule."""
        self._native.check()
        return self

    def to_dict(self):
        """Every field (nested structs as dicts), as the library writes them."""
        return self._tree()

    def from_dict(self, fields):
        """Sets the given fields (a nested dict, as to_dict gives); others keep their value."""
        for name, value in fields.items():
            if isinstance(value, dict):
                _assign(self, (name,), value)
            else:
                self._set((name,), value)
        return self

    @property
    def native(self):
        """The native _samp struct (for the calls of the _samp module)."""
        return self._native

    def __getstate__(self):
        return self._native.to_json()

    def __setstate__(self, state):
        object.__setattr__(self, "_native", self._native_type())
        self._native.from_json(state)

    def __eq__(self, other):
        return type(self) is type(other) and self.to_dict() == other.to_dict()

    def __repr__(self):
        return "%s(%s)" % (type(self).__name__, json.dumps(self.to_dict(), sort_keys=True))


def _assign(options, path, fields):
    for name, value in fields.items():
        if isinstance(value, dict):
            _assign(options, path + (name,), value)
        else:
            options._set(path + (name,), value)


def _checked(name, old, value):
    """The JSON value for field `name` (now `old`); refuses what would be converted silently."""
    if isinstance(old, dict):
        raise TypeError("field '%s' is a nested struct: set its fields one by one" % name)
    if hasattr(value, "tolist"):  # NumPy scalars and arrays
        value = value.tolist()
    if isinstance(old, bool):
        if not isinstance(value, bool):
            raise TypeError("field '%s' is a bool, got %r" % (name, value))
    elif isinstance(old, int):
        if isinstance(value, bool) or not isinstance(value, int):
            if isinstance(value, float) and value.is_integer():
                value = int(value)
            else:
                raise TypeError("field '%s' is an integer, got %r" % (name, value))
    elif isinstance(old, float):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise TypeError("field '%s' is a number, got %r" % (name, value))
        value = float(value)
    elif isinstance(old, str):
        if not isinstance(value, str):
            raise TypeError("field '%s' is a string, got %r" % (name, value))
    elif isinstance(old, list):
        if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
            raise TypeError("field '%s' is a list, got %r" % (name, value))
        value = [v.tolist() if hasattr(v, "tolist") else v for v in value]
    return value


class RunFitOptions(_Options):
    """`samp fit` as a whole (pipeline/run_fit.h RunFitOptions): model, sequences,
    output_dir, fit (FitOptions), sequence (SequenceOptions), num_threads,
    write_meshes, link_only. fit_sequence() sets model, sequences and output_dir."""

    _native_type = _samp.RunFitOptions


class FitOptions(_Options):
    """The fitter (fit/fitter.h FitOptions)."""

    _native_type = _samp.FitOptions


class SequenceOptions(_Options):
    """Reading a sequence (data/sequence.h SequenceOptions): stereo, road plane,
    observations, tracker."""

    _native_type = _samp.SequenceOptions


class TrainOptions(_Options):
    """`samp train` (model/trainer.h TrainOptions): cad_folder, manifest, preset,
    output, grid, scan, sdf, gate, pca, size_variants, num_threads, show_progress."""

    _native_type = _samp.TrainOptions
