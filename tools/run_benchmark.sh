#!/usr/bin/env bash
# Leave-out benchmark of samp (issues 4 and 11; docs/results.md, docs/synthetic.md, docs/evaluation.md):
#   1. train a shape model WITHOUT the evaluation cars (the hold-out of docs/cad_cars.md is
#      marked "skip" in a copy of models/cad_manifest.json; the road cars are never trained on),
#   2. per seed, synthesize a fixed set of stereo sequences of the test cars only (the realistic
#      street preset by default: StereoSGBM disparity, parked rows, traffic, clutter, a stereo
#      detector's errors; docs/synthetic.md),
#   3. fit every sequence with the full method (`samp fit` defaults: joint shape and motion,
#      ray-depth data term, mixture robustifier, effective weighting), the paper's energy
#      (--data-term paper --data-weighting mean --huber-loss --detection-size-sigma 0 --no-detection-position --shared-points) and --single-frame,
#   4. evaluate against the ground truth with the raw-stereo and input-detection baselines.
#
# Usage: tools/run_benchmark.sh [options]
#   --samp PATH           samp executable (default: build/tools/samp/samp under the repository)
#   --cad DIR             CAD cars folder (default: fetched by tools/get_cad_cars.sh into
#                         $SAMP_DATA_DIR/cad, or ~/.cache/samp/cad)
#   --no-road-cars        do not add the four road cars (hatchback, suv, pickup, prius: models/cad/,
#                         CAD_FOLDER/road/) to the test cars (default: they are test cars)
#   --work DIR            working folder (default: $SAMP_DATA_DIR/benchmark, or ~/.cache/samp/benchmark)
#   --holdout "A B ..."   Debian test cars (default: acura-nsx-sz car5-trb1, race-only bodies the
#                         road-traffic manifest skips anyway)
#   --size-variants "L H W; ..."  size variants of the training cars (samp train --size-variant;
#                         docs/training.md): default "1.15 1.0 1.05; 1.0 1.2 1.05; 1.12 1.25 1.12",
#                         "" = the CAD cars alone
#   --preset P            synth preset: street (default) or clean
#   --sequences N         synthetic sequences per seed (default 24)
#   --cars-per-sequence K traffic cars per sequence (default 3)
#   --parked-cars P       parked cars per sequence (street preset; default 3)
#   --seeds "S1 S2 ..."   synthesis seeds (default "2017 7 11"; the first one's tables are shown in full)
#   --clean-comparison    also run the clean preset on the first seed (the comparison table)
#   --profiles "P1 P2 ..." instead of the runs above: the street preset once per synthetic detector
#                         profile (samp synth --detector-profile; docs/synthetic.md "Detector profiles":
#                         default lidar stereo-x2 size-x3 kitti-boxes flips) and seed, each fitted with
#                         samp fit's DEFAULT flags (no tracker or detector flags: self-calibration) and
#                         with --detector-model = the profile's true noise model (SEQ/gt/detector_model.json),
#                         evaluated with the raw-stereo and detection baselines; the table "Across
#                         detectors" (tracks per car, main track, output on the car-frames with a
#                         detection, F1 per track) goes to WORK/profiles.md, and with --docs into
#                         docs/results.md. Runs: WORK/prof_<P>_<S>/{sequences,fit_full,fit_true,eval}
#   --threads T           worker threads (default 2)
#   --docs                also write docs/results.md and docs/images/benchmark_*.png
#   --retrain             train the model even when WORK/model_holdout.vdb is up to date
#   --reuse-sequences     keep WORK/<run>/sequences when its config.json exists (same options
#                         and seed give the same files; fits and evaluation are redone)
#   --reuse-runs          keep a whole run (sequences, fits, evaluation) when its
#                         eval/results.json exists, with its timings from WORK/timings.txt
#   -h, --help            this text
#
# Every step logs its command and duration to WORK/benchmark.log. Outputs:
#   WORK/model_holdout.vdb and per run (seed_<S>, clean_<S>) WORK/<run>/sequences/<seq>/,
#   fit_full/, fit_full_paper/, fit_single/, eval/ (with --profiles: see there).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
samp="$root/build/tools/samp/samp"
cad=""
work=""
holdout="acura-nsx-sz car5-trb1"
road_cars=1
preset=street
sequences=24
cars_per_sequence=3
parked_cars=3
seeds="2017 7 11"
clean_comparison=0
profiles=""
threads=2
write_docs=0
retrain=0
reuse_sequences=0
reuse_runs=0
size_variants="1.15 1.0 1.05; 1.0 1.2 1.05; 1.12 1.25 1.12"

usage() { sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed '$d' | sed 's/^# \{0,1\}//'; }
die() { echo "run_benchmark: error: $*" >&2; exit 1; }

while [ $# -gt 0 ]; do
  case "$1" in
    --samp) samp="$2"; shift 2 ;;
    --cad) cad="$2"; shift 2 ;;
    --work) work="$2"; shift 2 ;;
    --holdout) holdout="$2"; shift 2 ;;
    --no-road-cars) road_cars=0; shift ;;
    --size-variants) size_variants="$2"; shift 2 ;;
    --preset) preset="$2"; shift 2 ;;
    --sequences) sequences="$2"; shift 2 ;;
    --cars-per-sequence) cars_per_sequence="$2"; shift 2 ;;
    --parked-cars) parked_cars="$2"; shift 2 ;;
    --seeds) seeds="$2"; shift 2 ;;
    --clean-comparison) clean_comparison=1; shift ;;
    --profiles) profiles="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --docs) write_docs=1; shift ;;
    --retrain) retrain=1; shift ;;
    --reuse-sequences) reuse_sequences=1; shift ;;
    --reuse-runs) reuse_runs=1; shift ;;
    -h|--help) usage; exit 0 ;;
    *) usage >&2; die "unknown option '$1'" ;;
  esac
done

data="${SAMP_DATA_DIR:-$HOME/.cache/samp}"
[ -n "$work" ] || work="$data/benchmark"
[ -x "$samp" ] || die "samp executable '$samp' not found (build first: tools/build.sh, or give --samp)"
command -v python3 >/dev/null 2>&1 || die "python3 is needed to edit the manifest and write docs/results.md"
mkdir -p "$work"
work="$(cd "$work" && pwd)"
case "$work/" in "$root/"*) die "the working folder '$work' is inside the repository" ;; esac
log="$work/benchmark.log"
: > "$log"

step() {  # step NAME COMMAND...: runs, logs command and seconds
  local name="$1"; shift
  echo "run_benchmark: $name: $*" | tee -a "$log"
  local start end
  start=$(date +%s)
  "$@" >> "$log" 2>&1 || { tail -n 20 "$log" >&2; die "$name failed (log: $log)"; }
  end=$(date +%s)
  echo "run_benchmark: $name took $((end - start)) s" | tee -a "$log"
  echo "$name $((end - start))" >> "$work/timings.txt"
}
[ "$reuse_runs" = 1 ] && [ -f "$work/timings.txt" ] || : > "$work/timings.txt"

# 0. CAD cars.
if [ -z "$cad" ]; then
  step "get_cad_cars" "$root/tools/get_cad_cars.sh" "$data/cad"
  cad="$data/cad/cars"
fi
[ -d "$cad" ] || die "CAD folder '$cad' not found"
manifest="$root/models/cad_manifest.json"
[ -f "$manifest" ] || die "manifest '$manifest' not found"

# 1. Test cars, held out from the model: the four road cars (tools/get_cad_cars.sh copies the
#    repository's models/cad/ to CAD_FOLDER/road/) and the race-only hold-out.
test_cars="$holdout"
[ "$road_cars" = 1 ] && test_cars="$holdout hatchback suv pickup prius"
# The test manifest: models/cad_manifest.json with AddWheels' tyres under bodies that have none.
synth_manifest="$work/test_manifest.json"
python3 - "$manifest" "$synth_manifest" <<'EOF'
import json, sys
m = json.load(open(sys.argv[1]))
m.setdefault("defaults", {}).setdefault("wheels", "synthesise")
json.dump(m, open(sys.argv[2], "w"), indent=2)
EOF
echo "run_benchmark: test cars: $test_cars" | tee -a "$log"
car_args=()
for car in $test_cars; do car_args+=(--car "$car"); done

# 2. Training manifest without the test cars, and the model.
train_manifest="$work/train_manifest.json"
python3 - "$manifest" "$train_manifest.new" "$holdout" $test_cars <<'EOF'
import json, sys
source, target, holdout, test = sys.argv[1], sys.argv[2], set(sys.argv[3].split()), set(sys.argv[4:])
m = json.load(open(source))
m.setdefault("defaults", {}).setdefault("wheels", "synthesise")  # as the test cars (AddWheels)
found = set()
for entry in m["models"]:
    if entry.get("name") in test:
        found.add(entry["name"])
        if not entry.get("skip"):
            entry["skip"] = True
            entry["skip_reason"] = "held out for the leave-out evaluation (tools/run_benchmark.sh)"
missing = holdout - found
if missing:
    sys.exit("hold-out cars not in the manifest: " + ", ".join(sorted(missing)))
json.dump(m, open(target, "w"), indent=2)
used = sum(1 for entry in m["models"] if not entry.get("skip"))
open(target + ".used", "w").write(str(used))
EOF
used_cars=$(cat "$train_manifest.new.used")
rm -f "$train_manifest.new.used"
variant_args=()
num_variants=0
IFS=';' read -ra variant_list <<< "$size_variants"
for v in "${variant_list[@]}"; do
  read -ra factors <<< "$v"
  [ "${#factors[@]}" = 0 ] && continue
  [ "${#factors[@]}" = 3 ] || die "--size-variants: '$v' is not three factors (length height width)"
  variant_args+=(--size-variant "${factors[@]}")
  num_variants=$((num_variants + 1))
done
# R = 5 components need >= 6 training shapes (cars and their size variants); with fewer, R = shapes - 1.
shapes=$((used_cars * (1 + num_variants)))
rank=$((shapes - 1 < 5 ? shapes - 1 : 5))
[ "$rank" -ge 1 ] || rank=1
echo "run_benchmark: $used_cars training cars of the manifest, $shapes shapes: R = $rank components; size variants: ${size_variants:-none}" \
  | tee -a "$log"
model="$work/model_holdout.vdb"
echo "$rank ${variant_args[*]:-}" > "$train_manifest.new.args"
if [ "$retrain" = 1 ] || [ ! -f "$model" ] || ! cmp -s "$train_manifest.new" "$train_manifest" \
  || ! cmp -s "$train_manifest.new.args" "$train_manifest.args"; then
  mv "$train_manifest.new" "$train_manifest"
  mv "$train_manifest.new.args" "$train_manifest.args"
  rm -f "$model"
  step "train" "$samp" train "$cad" --manifest "$train_manifest" -R "$rank" "${variant_args[@]}" -o "$model" \
    --threads "$threads" -q
else
  rm -f "$train_manifest.new" "$train_manifest.new.args"
  echo "run_benchmark: train: $model is up to date (--retrain to redo)" | tee -a "$log"
fi

# 3-4. Per seed (and the clean comparison): synth, the three fits, evaluation.
run_one() {  # run_one NAME PRESET SEED
  local name="$1" run_preset="$2" run_seed="$3"
  local dir="$work/$name"
  if [ "$reuse_runs" = 1 ] && [ -f "$dir/eval/results.json" ]; then
    echo "run_benchmark: $name: reusing the whole run in $dir" | tee -a "$log"
    return 0
  fi
  local extra=()
  [ "$run_preset" = street ] && extra=(--parked-cars "$parked_cars")
  # The tracker's noise model is the detector's (docs/fitting.md, "Tracking"): samp fit's defaults are
  # the street preset's stereo detector; the clean preset's detector (docs/synthetic.md) errs by
  # 0.1 + 0.001 d^2 m along the ray, 0.05 + 0.005 d across and 0.05 m vertically, white.
  local fit_extra=()
  [ "$run_preset" = clean ] && fit_extra=(--tracker-along-sigma 0.1,0,0.001 --tracker-across-sigma 0.05,0.005
                                          --tracker-vertical-sigma 0.05,0)
  if [ "$reuse_sequences" = 1 ] && [ -f "$dir/sequences/config.json" ]; then
    echo "run_benchmark: $name: reusing $dir/sequences" | tee -a "$log"
    rm -rf "$dir/fit_full" "$dir/fit_full_paper" "$dir/fit_single" "$dir/eval"
  else
  rm -rf "$dir"
  mkdir -p "$dir"
  step "$name/synth" "$samp" synth --cad "$cad" --manifest "$synth_manifest" "${car_args[@]}" \
    --preset "$run_preset" --sequences "$sequences" --cars-per-sequence "$cars_per_sequence" "${extra[@]}" \
    --seed "$run_seed" --disparity sgbm -o "$dir/sequences"
  fi
  local seq_args=()
  local seq
  for seq in "$dir"/sequences/[0-9][0-9][0-9][0-9][0-9][0-9]; do seq_args+=(--seq "$seq"); done
  step "$name/fit_full" "$samp" fit --model "$model" "${seq_args[@]}" "${fit_extra[@]}" --out "$dir/fit_full" --threads "$threads" -q
  step "$name/fit_full_paper" "$samp" fit --model "$model" "${seq_args[@]}" "${fit_extra[@]}" \
    --data-term paper --data-weighting mean --huber-loss --detection-size-sigma 0 --no-detection-position --shared-points --out "$dir/fit_full_paper" --threads "$threads" -q
  step "$name/fit_single" "$samp" fit --model "$model" "${seq_args[@]}" "${fit_extra[@]}" --single-frame \
    --out "$dir/fit_single" --threads "$threads" -q
  step "$name/eval" "$samp" eval "${seq_args[@]}" --result "full=$dir/fit_full" \
    --result "full-paper=$dir/fit_full_paper" --result "single-frame=$dir/fit_single" \
    --out "$dir/eval" --threads "$threads" --pictures -q
}
# Across detectors (--profiles): per profile and seed, synth with the profile's detector, fit with the
# defaults and with the true noise model, evaluate.
run_profile() {  # run_profile NAME PROFILE SEED
  local name="$1" profile="$2" run_seed="$3"
  local dir="$work/$name"
  if [ "$reuse_runs" = 1 ] && [ -f "$dir/eval/results.json" ]; then
    echo "run_benchmark: $name: reusing the whole run in $dir" | tee -a "$log"
    return 0
  fi
  if [ "$reuse_sequences" = 1 ] && [ -f "$dir/sequences/config.json" ]; then
    echo "run_benchmark: $name: reusing $dir/sequences" | tee -a "$log"
    rm -rf "$dir/fit_full" "$dir/fit_true" "$dir/eval"
  else
    rm -rf "$dir"
    mkdir -p "$dir"
    step "$name/synth" "$samp" synth --cad "$cad" --manifest "$synth_manifest" "${car_args[@]}" \
      --preset street --detector-profile "$profile" --sequences "$sequences" \
      --cars-per-sequence "$cars_per_sequence" --parked-cars "$parked_cars" --seed "$run_seed" \
      --disparity sgbm -o "$dir/sequences"
  fi
  local seq_args=()
  local seq first_seq=""
  for seq in "$dir"/sequences/[0-9][0-9][0-9][0-9][0-9][0-9]; do
    seq_args+=(--seq "$seq")
    [ -n "$first_seq" ] || first_seq="$seq"
  done
  local true_model="$first_seq/gt/detector_model.json"
  [ -f "$true_model" ] || die "$true_model not found (a samp synth without detector models?)"
  step "$name/fit_full" "$samp" fit --model "$model" "${seq_args[@]}" --out "$dir/fit_full" --threads "$threads" -q
  step "$name/fit_true" "$samp" fit --model "$model" "${seq_args[@]}" --detector-model "$true_model" \
    --out "$dir/fit_true" --threads "$threads" -q
  step "$name/eval" "$samp" eval "${seq_args[@]}" --result "full=$dir/fit_full" \
    --result "true-model=$dir/fit_true" --out "$dir/eval" --threads "$threads" -q
}
if [ -n "$profiles" ]; then
  profile_runs=()
  for s in $seeds; do
    for p in $profiles; do
      run_profile "prof_${p}_$s" "$p" "$s"
      profile_runs+=("prof_${p}_$s")
    done
  done
  total=$(awk '{s += $2} END {print s + 0}' "$work/timings.txt")
  echo "run_benchmark: total $total s" | tee -a "$log"
  docs_args=()
  [ "$write_docs" = 1 ] && docs_args=(--results "$root/docs/results.md")
  python3 "$root/tools/benchmark_report.py" profiles --work "$work" --profiles "$profiles" --seeds "$seeds" \
    --sequences "$sequences" --cars "$cars_per_sequence" --parked "$parked_cars" --threads "$threads" \
    --total "$total" --cores "$(nproc)" --out "$work/profiles.md" "${docs_args[@]}"
  cat "$work/profiles.md"
  [ "$write_docs" = 1 ] && echo "run_benchmark: wrote the section \"Across detectors\" of $root/docs/results.md"
  exit 0
fi

runs=()
for s in $seeds; do
  run_one "seed_$s" "$preset" "$s"
  runs+=("seed_$s")
done
first_seed="${seeds%% *}"
if [ "$clean_comparison" = 1 ] && [ "$preset" != clean ]; then
  run_one "clean_$first_seed" clean "$first_seed"
  runs+=("clean_$first_seed")
fi
# The steps of this run and of the runs it reused (WORK/timings.txt).
total=$(awk '{s += $2} END {print s + 0}' "$work/timings.txt")
echo "run_benchmark: total $total s" | tee -a "$log"
cat "$work/seed_$first_seed/eval/results.md"

# 5. docs/results.md (generated part; text below the "<!-- notes -->" line is kept).
if [ "$write_docs" = 1 ]; then
  mkdir -p "$root/docs/images"
  for plot in f1_vs_tau accuracy_vs_tau completeness_vs_tau translation_vs_distance yaw_vs_distance; do
    cp "$work/seed_$first_seed/eval/$plot.png" "$root/docs/images/benchmark_$plot.png"
  done
  python3 "$root/tools/benchmark_report.py" --results "$root/docs/results.md" --work "$work" \
    --runs "${runs[*]}" --test-cars "$test_cars" --holdout "$holdout" --preset "$preset" \
    --size-variants "$size_variants" --rank "$rank" \
    --sequences "$sequences" --cars "$cars_per_sequence" --parked "$parked_cars" --threads "$threads" \
    --total "$total" --cores "$(nproc)"
  echo "run_benchmark: wrote $root/docs/results.md and docs/images/benchmark_*.png"
fi
