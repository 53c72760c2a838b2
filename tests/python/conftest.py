"""Shared fixtures of the Python tests (ctest python/...): the shipped model, the real
KITTI frame of ../shared (SAMP_SHARED_DIR), copies of it as small sequences."""

import os
import shutil

import pytest


def shipped_model():
    return os.environ["SAMP_SHIPPED_MODEL"]


def kitti_frame_dir():
    return os.path.join(os.environ["SAMP_SHARED_DIR"], "kitti", "000046")


def require_kitti():
    d = kitti_frame_dir()
    if not os.path.isdir(d):
        pytest.skip("%s not present" % d)
    return d


def copy_sequence(source, dest, name):
    """The sequence `source` (frame files named after its calib stem) under a new name:
    every file whose name starts with the old stem is renamed to start with `name`."""
    stem = os.path.splitext(os.listdir(os.path.join(source, "calib"))[0])[0]
    for root, _, files in os.walk(source):
        rel = os.path.relpath(root, source)
        os.makedirs(os.path.join(dest, rel), exist_ok=True)
        for f in files:
            new = name + f[len(stem):] if f.startswith(stem) else f
            shutil.copyfile(os.path.join(root, f), os.path.join(dest, rel, new))
    return dest


def make_sequence_root(root, count):
    """`count` copies of the real KITTI frame as sequences root/seq_NN (named 0001NN)."""
    source = require_kitti()
    os.makedirs(root, exist_ok=True)
    names = []
    for i in range(count):
        name = "seq_%02d" % i
        copy_sequence(source, os.path.join(root, name), "%06d" % (100 + i))
        names.append(name)
    return names


def tree_bytes(folder):
    """{relative path: bytes} of every file under folder."""
    out = {}
    for root, _, files in os.walk(folder):
        for f in files:
            p = os.path.join(root, f)
            with open(p, "rb") as fh:
                out[os.path.relpath(p, folder)] = fh.read()
    return out


def without_timings(name, data):
    """A file's bytes, with the wall-clock times of tracks.json ("seconds",
    "median_step_seconds": they differ between two runs of samp fit itself)
    replaced by 0; every other byte is kept."""
    if os.path.basename(name) != "tracks.json":
        return data
    import re
    return re.sub(rb'("(?:[a-z_]*_)?seconds": )[-0-9.eE+]+', rb"\g<1>0", data)


def assert_same_files(got, expected, what=""):
    """Same file names; every file byte for byte, tracks.json up to its timings."""
    assert sorted(got) == sorted(expected), what
    for name in expected:
        assert without_timings(name, got[name]) == without_timings(name, expected[name]), \
            "%s%s differs" % (what + "/" if what else "", name)
