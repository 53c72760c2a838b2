#!/usr/bin/env python3
"""Measures the stereo disparity errors on car pixels of `samp synth` sequences.

For each car-frame (gt/obj_map) it compares the disparity the fitter reads
(disparity/<seq>_<ff>.png) with the true one, f b / z of gt/depth, and reports
  - the mean absolute disparity error on car pixels (the benchmark's calibration figure),
  - the robust standard deviation of the error (1.4826 MAD),
  - the correlation area A = sum over image lags of the error's normalised
    autocorrelation within the car: the image area of one independent
    observation, so that N pixels carry about N / A independent ones. The
    fitter's effective weighting (docs/fitting.md, "Prior/data balance",
    --correlation-area) uses this figure.
Errors beyond --clip px are clipped (wrong matches would dominate the variance).

Usage: tools/stereo_error_correlation.py SEQ_DIR [SEQ_DIR ...] [--frames middle|all] [--max-lag 12]
Needs python3-numpy and python3-pil (Debian). Reads the layout of docs/sequence_format.md and
docs/synthetic.md.
"""
import argparse
import glob
import os
import sys

try:
    import numpy as np
    from PIL import Image
except ImportError as e:  # pragma: no cover
    sys.exit(f"stereo_error_correlation: {e}: install python3-numpy and python3-pil")


def read_png16(path):
    return np.asarray(Image.open(path), dtype=np.float64)


def calibration(seq):
    files = sorted(glob.glob(os.path.join(seq, "calib", "*.txt")))
    if not files:
        sys.exit(f"stereo_error_correlation: no calib/*.txt in {seq}")
    rows = {}
    with open(files[0]) as f:
        for line in f:
            key, _, values = line.partition(":")
            rows[key.strip()] = [float(v) for v in values.split()]
    p2, p3 = rows["P2"], rows["P3"]
    focal = p2[0]
    baseline = (p2[3] - p3[3]) / focal
    return focal, baseline


def car_frames(seq, frames):
    maps = sorted(glob.glob(os.path.join(seq, "gt", "obj_map", "*.png")))
    if not maps:
        sys.exit(f"stereo_error_correlation: no gt/obj_map/*.png in {seq}")
    if frames == "middle":
        maps = [maps[len(maps) // 2]]
    for m in maps:
        name = os.path.basename(m)
        yield (m, os.path.join(seq, "gt", "depth", name), os.path.join(seq, "disparity", name))


def correlation_area(error, max_lag):
    """Sum of the normalised autocorrelation of `error` (NaN = no sample) over lags."""
    valid = ~np.isnan(error)
    e = np.where(valid, error - np.nanmean(error), 0.0)
    var = np.sum(e * e) / max(valid.sum(), 1)
    if var <= 0:
        return None
    h, w = e.shape
    area = 0.0
    for dy in range(-max_lag, max_lag + 1):
        for dx in range(-max_lag, max_lag + 1):
            a = e[max(0, dy):h + min(0, dy), max(0, dx):w + min(0, dx)]
            b = e[max(0, -dy):h + min(0, -dy), max(0, -dx):w + min(0, -dx)]
            va = valid[max(0, dy):h + min(0, dy), max(0, dx):w + min(0, dx)]
            vb = valid[max(0, -dy):h + min(0, -dy), max(0, -dx):w + min(0, -dx)]
            both = va & vb
            n = both.sum()
            if n < 20:
                continue
            area += np.sum(a[both] * b[both]) / n / var
    return area


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("sequences", nargs="+")
    parser.add_argument("--frames", choices=["middle", "all"], default="middle")
    parser.add_argument("--max-lag", type=int, default=12, help="largest image lag, px (default 12)")
    parser.add_argument("--clip", type=float, default=5.0, help="clip |error| at this, px (default 5)")
    parser.add_argument("--min-pixels", type=int, default=200, help="cars with fewer valid pixels are skipped")
    args = parser.parse_args()
    abs_errors, areas, sigmas = [], [], []
    for seq in args.sequences:
        focal, baseline = calibration(seq)
        for obj_path, depth_path, disp_path in car_frames(seq, args.frames):
            if not (os.path.exists(depth_path) and os.path.exists(disp_path)):
                continue
            obj = np.asarray(Image.open(obj_path))
            depth = read_png16(depth_path) / 256.0
            disparity = read_png16(disp_path) / 256.0
            true_disparity = np.where(depth > 0, focal * baseline / np.maximum(depth, 1e-9), 0.0)
            for car in np.unique(obj):
                if car == 0:
                    continue
                mask = (obj == car) & (depth > 0) & (disparity > 0)
                if mask.sum() < args.min_pixels:
                    continue
                err = disparity - true_disparity
                abs_errors.append(np.abs(err[mask]))
                clipped = np.where(mask, np.clip(err, -args.clip, args.clip), np.nan)
                sigmas.append(1.4826 * np.median(np.abs(err[mask] - np.median(err[mask]))))
                a = correlation_area(clipped, args.max_lag)
                if a is not None:
                    areas.append(a)
    if not abs_errors:
        sys.exit("stereo_error_correlation: no car pixels with disparity and depth found")
    all_abs = np.concatenate(abs_errors)
    print(f"car-frames: {len(areas)}, car pixels: {all_abs.size}")
    print(f"mean absolute disparity error on car pixels: {all_abs.mean():.3f} px (median {np.median(all_abs):.3f} px)")
    print(f"robust std. dev. per car-frame (median): {np.median(sigmas):.3f} px")
    print(f"correlation area per car-frame: median {np.median(areas):.1f} px, "
          f"quartiles {np.percentile(areas, 25):.1f} / {np.percentile(areas, 75):.1f} px "
          f"(max lag {args.max_lag} px, errors clipped at {args.clip} px)")


if __name__ == "__main__":
    main()
