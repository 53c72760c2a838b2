#!/usr/bin/env bash
# README command 1: the main job on the embedded default, end to end.
#   1. install missing Debian packages and build samp,
#   2. fetch the real CAD cars from Debian (torcs-data, trigger-rally-data) into a cache,
#   3. inspect the shipped model (models/samp_cars_r5.vdb): summary, eigen-shape meshes and pictures,
#   4. leave-out run (tools/run_benchmark.sh, one seed): train a model without the evaluation
#      cars, synthesize street stereo sequences of the held-out cars, fit them (the full method
#      with samp's defaults, the paper's energy, and single-frame), evaluate against the ground
#      truth (tables and plots),
#   5. pictures and an offline viewer page of every fit.
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
  --sequences "${DEMO_SEQUENCES:-2}" --cars-per-sequence 2 --seeds 2017
run="$out/benchmark/seed_2017"
fits=(fit_full fit_full_paper fit_single)

echo "== Pictures and viewers of the fits"
for fit in "${fits[@]}"; do
  "$samp" view "$run/$fit" --pictures -q
done

echo
echo "samp demo: outputs in $out"
echo "  model_summary.txt, eigen_shapes/*.ply, pictures/*.png"
echo "  benchmark/model_holdout.vdb (the leave-out model), benchmark/seed_2017/sequences (synthetic stereo +"
echo "  ground truth), benchmark/seed_2017/fit_full (defaults), fit_full_paper (the paper's energy), fit_single"
echo "  benchmark/seed_2017/eval/results.md and *.png (accuracy/completeness/F1 vs tau, pose error vs distance)"
echo "  benchmark/seed_2017/eval/error_surfaces/<method>/<seq>/track_<id>_error.png (surfaces coloured by error at tau)"
echo
echo "Pictures of the fits (docs/fitting.md, \"Pictures\"):"
for fit in "${fits[@]}"; do
  for sheet in "$run/$fit"/pictures/*/birdseye.png; do
    [ -e "$sheet" ] || continue
    folder="$(dirname "$sheet")"
    echo "  $folder/: birdseye.png, $(cd "$folder" && ls track_*.png | wc -l) track pictures (track_<id>_{overlay,birdseye,shape,error}.png)"
  done
done
echo "Interactive viewers (open in a browser; they work offline):"
for fit in "${fits[@]}"; do
  echo "  $run/$fit/index.html"
done
echo "  $out/pictures/inspect.html (eigen-shape sliders of the shipped model)"
