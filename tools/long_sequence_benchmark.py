#!/usr/bin/env python3
"""Long tracks: one solve over the whole sequence against fitting it in windows.

Issue 31 asks whether a track of 300 frames is fitted in one solve or in
overlapping windows: "a 300-frame sequence fits in <= 2x the time of 15 windows
of 21 frames, with memory <= 2 GB". This script measures it (docs/benchmarks.md,
"Long sequences"):

  1. `samp synth` one street sequence of --frames frames (default 301) with a slow
     ego car (--max-ego-speed 1 m/s), so that cars stay in view for the whole
     sequence (they stand); with --moving, traffic that drives along with the
     ego car instead (ego 8 m/s straight, cars 7-9 m/s, no parked rows);
  2. `samp fit` it once over all frames (one solve per track, samp's behaviour);
  3. `samp fit --frames A-B` once per window of --window frames (default 21;
     consecutive windows share one frame: 0-20, 20-40, ..., 280-300);
  4. prints a Markdown table: tracks, track-frames, the solves' seconds (the sum of
     tracks.json's per-track "seconds"), wall-clock seconds and peak RSS of each
     process, and the ratios one solve / all windows.

Every fit runs with --threads 1 (one core: the ratio does not depend on how
many cores the machine lends). Usage:

  python3 tools/long_sequence_benchmark.py --cad CAD_FOLDER [--work DIR] [--samp PATH]
      [--model MODEL.vdb] [--frames 301] [--window 21] [--seed 11] [--cars 4] [--moving]
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent


def run(command, log):
    """Runs command with output to log; returns (wall seconds, peak RSS MB) of that process."""
    start = time.monotonic()
    with open(log, "w") as out:
        process = subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT)
        _, status, usage = os.wait4(process.pid, 0)
    wall = time.monotonic() - start
    code = os.waitstatus_to_exitcode(status)
    if code != 0:
        sys.exit(f"long_sequence_benchmark: {' '.join(map(str, command))} exited {code}; see {log}")
    return wall, usage.ru_maxrss / 1024.0


def fit_figures(out):
    """Tracks, track-frames, longest track and the solves' seconds of one samp fit output."""
    data = json.loads((out / "tracks.json").read_text())
    tracks = [t for s in data["sequences"] for t in s["tracks"]]
    return (len(tracks), sum(len(t["frames"]) for t in tracks), max((len(t["frames"]) for t in tracks), default=0),
            sum(t["summary"]["seconds"] for t in tracks))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--samp", default=str(ROOT / "build/tools/samp/samp"))
    ap.add_argument("--cad", required=True, help="CAD cars folder (tools/get_cad_cars.sh)")
    ap.add_argument("--manifest", default=str(ROOT / "models/cad_manifest.json"))
    ap.add_argument("--model", default=str(ROOT / "models/samp_cars_r5.vdb"))
    ap.add_argument("--work", default=os.path.join(os.environ.get("SAMP_DATA_DIR", os.path.expanduser("~/.cache/samp")),
                                                   "long_sequence"))
    ap.add_argument("--frames", type=int, default=301)
    ap.add_argument("--window", type=int, default=21)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--cars", type=int, default=4)
    ap.add_argument("--moving", action="store_true", help="traffic driving along with the ego car")
    a = ap.parse_args()
    if a.window < 2 or a.frames < a.window:
        sys.exit("long_sequence_benchmark: need 2 <= --window <= --frames")
    work = pathlib.Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    sequences = work / "sequences"
    run([a.samp, "synth", "--cad", a.cad, "--manifest", a.manifest, "--seed", str(a.seed), "--sequences", "1",
         "--cars-per-sequence", str(a.cars), "--frames", str(a.frames), "--out", str(sequences), "--quiet"] +
        (["--parked-cars", "0", "--min-ego-speed", "8", "--max-ego-speed", "8", "--max-ego-yaw-rate", "0",
          "--min-speed", "7", "--max-speed", "9"] if a.moving else ["--max-ego-speed", "1"]), work / "synth.log")
    sequence = sequences / "000000"
    fit = [a.samp, "fit", "--seq", str(sequence), "--model", a.model, "--threads", "1", "--quiet"]

    rows = []
    wall, rss = run(fit + ["--out", str(work / "whole")], work / "whole.log")
    rows.append((f"one solve, frames 0-{a.frames - 1}", *fit_figures(work / "whole"), wall, rss))
    step = a.window - 1
    windows = []
    for first in range(0, a.frames - 1, step):
        last = min(first + step, a.frames - 1)
        out = work / f"window_{first:04d}"
        wall, rss = run(fit + ["--out", str(out), "--frames", f"{first}-{last}"], work / f"window_{first:04d}.log")
        windows.append((*fit_figures(out), wall, rss))
    total = (sum(w[0] for w in windows), sum(w[1] for w in windows), max(w[2] for w in windows),
             sum(w[3] for w in windows), sum(w[4] for w in windows), max(w[5] for w in windows))
    rows.append((f"{len(windows)} windows of {a.window} frames (sum; longest, peak RSS: max)", *total))

    print(f"| fit | tracks | track-frames | longest track | solves, s | wall, s | peak RSS, MB |")
    print("|---|---|---|---|---|---|---|")
    for name, tracks, frames, longest, solve, wall, rss in rows:
        print(f"| {name} | {tracks} | {frames} | {longest} | {solve:.2f} | {wall:.1f} | {rss:.0f} |")
    whole, split = rows[0], rows[1]
    print(f"\none solve / windows: solves {whole[4] / split[4]:.2f}x, wall {whole[5] / split[5]:.2f}x; "
          f"peak RSS of the one solve {whole[6]:.0f} MB")


if __name__ == "__main__":
    main()
