#!/usr/bin/env bash
# README command 1: the main job on the embedded default, end to end.
#   1. install missing Debian packages and build samp,
#   2. fetch the real CAD cars from Debian (torcs-data, trigger-rally-data) into a cache,
#   3. inspect the shipped model (models/samp_cars_r5.vdb): summary, eigen-shape meshes and pictures,
#   4. leave-out run: train a model without the evaluation cars, synthesize stereo sequences
#      of the held-out cars, fit them (full method with the paper's data term and with the
#      ray-distance data term, and single-frame), evaluate against the ground truth (tables
#      and plots).
# Usage: tools/demo.sh [OUT_DIR]   (default: $SAMP_DATA_DIR/demo or ~/.cache/samp/demo;
#        it must lie outside the repository). Set DEMO_SEQUENCES (default 2) for a larger run.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
data="${SAMP_DATA_DIR:-$HOME/.cache/samp}"
out="${1:-$data/demo}"
mkdir -p "$out"
out="$(cd "$out" && pwd)"

bash "$root/tools/build.sh"
samp="${SAMP_BUILD_DIR:-$root/build}/tools/samp/samp"

echo "== CAD cars"
bash "$root/tools/get_cad_cars.sh" "$data/cad"

echo "== The shipped model"
"$samp" inspect "$root/models/samp_cars_r5.vdb" | tee "$out/model_summary.txt"
"$samp" inspect "$root/models/samp_cars_r5.vdb" --meshes "$out/eigen_shapes" --pictures "$out/pictures" \
  --cad-dir "$data/cad/cars" --manifest "$root/models/cad_manifest.json" --html "$out/pictures/inspect.html" -q

echo "== Leave-out fit and evaluation on synthetic stereo"
bash "$root/tools/run_benchmark.sh" --samp "$samp" --cad "$data/cad/cars" --work "$out/benchmark" \
  --sequences "${DEMO_SEQUENCES:-2}" --cars-per-sequence 2

echo "== Pictures and viewers of the fits"
for fit in fit_full fit_full_ray fit_single; do
  "$samp" view "$out/benchmark/$fit" --pictures -q
done

echo
echo "samp demo: outputs in $out"
echo "  model_summary.txt, eigen_shapes/*.ply, pictures/*.png"
echo "  benchmark/sequences (synthetic stereo + ground truth), benchmark/fit_full, benchmark/fit_full_ray,"
echo "  benchmark/fit_single"
echo "  benchmark/eval/results.md and *.png (accuracy/completeness/F1 vs tau, pose error vs distance)"
echo "  benchmark/eval/error_surfaces/<method>/<seq>/track_<id>_error.png (surfaces coloured by error at tau)"
echo
echo "Pictures of the fits (docs/fitting.md, \"Pictures\"):"
for fit in fit_full fit_full_ray fit_single; do
  for sheet in "$out/benchmark/$fit"/pictures/*/birdseye.png; do
    [ -e "$sheet" ] || continue
    folder="$(dirname "$sheet")"
    echo "  $folder/: birdseye.png, $(cd "$folder" && ls track_*.png | wc -l) track pictures (track_<id>_{overlay,birdseye,shape,error}.png)"
  done
done
echo "Interactive viewers (open in a browser; they work offline):"
for fit in fit_full fit_full_ray fit_single; do
  echo "  $out/benchmark/$fit/index.html"
done
echo "  $out/pictures/inspect.html (eigen-shape sliders of the shipped model)"
