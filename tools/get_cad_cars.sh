#!/usr/bin/env bash
# Obtains the real CAD cars samp trains on from two Debian 12 packages, without
# installing the games:
#   torcs-data          17 TORCS cars, usr/share/games/torcs/cars/<name>/<name>.acc (AC3D)
#   trigger-rally-data  3 distinct Trigger Rally bodies in usr/share/games/trigger-rally/data.zip,
#                       vehicles/<body>_wrc/<body>_wrc.obj (Wavefront OBJ; wheels are separate
#                       files and are not taken; the _kitcar/_super500 variants have the same
#                       geometry and differ only in texture)
# and adds the four road cars vendored in the repository (models/cad/: Gazebo hatchback, SUV,
# pickup and Prius, CC BY 3.0, models/cad/README.md) under CACHE_DIR/cars/road/.
#
# Usage: tools/get_cad_cars.sh [CACHE_DIR]
#   CACHE_DIR defaults to $SAMP_DATA_DIR/cad, or ~/.cache/samp/cad when SAMP_DATA_DIR is unset.
#
# Result (the folder to train on is CACHE_DIR/cars):
#   CACHE_DIR/cars/torcs/<name>.acc            the 17 TORCS bodies (main model, not the LODs)
#   CACHE_DIR/cars/trigger/<body>_wrc.obj/.mtl the 3 Trigger Rally bodies
#   CACHE_DIR/cars/road/gazebo_models/...      a copy of models/cad/gazebo_models (4 road cars)
#   CACHE_DIR/cars/cad_manifest.json           a copy of models/cad_manifest.json
#   CACHE_DIR/cars/SOURCES.txt                 package versions and SHA-256 of every file
#   CACHE_DIR/debs, CACHE_DIR/extract          the downloaded packages and their contents
# Then: samp train CACHE_DIR/cars --manifest models/cad_manifest.json -o MODEL.vdb
#
# Idempotent: a step whose result exists is skipped; delete CACHE_DIR to start afresh.
# Needs apt-get, dpkg-deb and unzip; `apt-get update` (root or sudo) only when the
# package lists do not know the packages yet. docs/cad_cars.md describes the cars.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
manifest_src="$root/models/cad_manifest.json"
if [ $# -gt 1 ]; then
  echo "usage: tools/get_cad_cars.sh [CACHE_DIR]   (--help for details)" >&2
  exit 2
fi
if [ "${1:-}" = "-h" ] || [ "${1:-}" = "--help" ]; then
  sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed '$d' | sed 's/^# \{0,1\}//'
  exit 0
fi
if [ $# -eq 1 ]; then
  cache="$1"
elif [ -n "${SAMP_DATA_DIR:-}" ]; then
  cache="$SAMP_DATA_DIR/cad"
else
  cache="$HOME/.cache/samp/cad"
fi

die() { echo "get_cad_cars: error: $*" >&2; exit 1; }
say() { echo "get_cad_cars: $*"; }
# collect SRC DST WHERE: copies SRC (which must exist; WHERE names its package)
# to DST atomically, unless DST already holds the same bytes.
collect() {
  [ -f "$1" ] || die "$1 missing from $3"
  if ! cmp -s "$1" "$2"; then
    cp "$1" "$2.tmp" && mv "$2.tmp" "$2"
  fi
}

for tool in apt-get apt-cache dpkg-deb unzip sha256sum; do
  command -v "$tool" >/dev/null 2>&1 || die "'$tool' not found (this script needs Debian's apt/dpkg tools and unzip: apt-get install unzip)"
done

torcs_cars=(155-DTM acura-nsx-sz baja-bug buggy car1-ow1 car1-stock1 car1-stock2 car1-trb1
            car1-trb3 car2-trb1 car3-trb1 car4-trb1 car5-trb1 car6-trb1 car7-trb1 car8-trb1 p406)
trigger_bodies=(cordo evo fox)
packages=(torcs-data trigger-rally-data)

cache="$(realpath -m -- "$cache")"
case "$cache/" in
  "$root/"*) die "the cache '$cache' is inside the repository; give a folder outside it" ;;
esac
mkdir -p "$cache" || die "cannot create cache folder '$cache'"
debs="$cache/debs"
extract="$cache/extract"
cars="$cache/cars"
mkdir -p "$debs" "$extract" "$cars/torcs" "$cars/trigger"

# 1. Download the packages (skipped when a valid .deb is already there).
# The .deb of package $1 in folder $2 (default: $debs), or nothing.
deb_of() {
  local f
  for f in "${2:-$debs}/$1"_*_all.deb; do
    [ -f "$f" ] && { echo "$f"; return 0; }
  done
  return 0
}
need_download=()
for p in "${packages[@]}"; do
  deb="$(deb_of "$p")"
  if [ -n "$deb" ] && dpkg-deb --info "$deb" >/dev/null 2>&1; then
    say "have $(basename "$deb")"
  else
    [ -n "$deb" ] && rm -f "$deb"
    need_download+=("$p")
  fi
done
if [ ${#need_download[@]} -gt 0 ]; then
  for p in "${need_download[@]}"; do
    candidate="$(apt-cache policy "$p" 2>/dev/null | awk '/Candidate:/ {print $2}')"
    if [ -z "$candidate" ] || [ "$candidate" = "(none)" ]; then
      say "the package lists do not know $p; running apt-get update"
      sudo_cmd=()
      [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
      "${sudo_cmd[@]}" apt-get update -qq || die "apt-get update failed"
      break
    fi
  done
  say "downloading ${need_download[*]} (about 450 MB) into $debs"
  tmp="$(mktemp -d "$debs/.download.XXXXXX")"
  trap 'rm -rf "$tmp"' EXIT
  # apt-get download writes into the current folder; a partial file never reaches $debs.
  # The _apt sandbox user cannot write to a private folder; download as the caller.
  (cd "$tmp" && apt-get download -q -o APT::Sandbox::User="$(id -un)" "${need_download[@]}") ||
    die "apt-get download ${need_download[*]} failed (network? 'deb' sources for bookworm main in /etc/apt/sources.list*?)"
  for p in "${need_download[@]}"; do
    deb="$(deb_of "$p" "$tmp")"
    [ -n "$deb" ] || die "apt-get download did not produce $p's .deb"
    dpkg-deb --info "$deb" >/dev/null 2>&1 || die "downloaded $(basename "$deb") is not a valid .deb"
    mv "$deb" "$debs/"
    say "downloaded $(basename "$deb")"
  done
  rm -rf "$tmp"
  trap - EXIT
fi

# 2. Unpack each package with dpkg -x (skipped when the stamp names the same .deb).
for p in "${packages[@]}"; do
  deb="$(deb_of "$p")"
  stamp="$extract/$p.done"
  # The stamp holds "<package> <version> <sha256 of the .deb>" of the unpacked .deb.
  if [ -f "$stamp" ] && [ "$(cut -d' ' -f1 "$stamp")" = "$(basename "$deb")" ]; then
    say "have $p unpacked"
    continue
  fi
  say "unpacking $(basename "$deb")"
  rm -rf "${extract:?}/$p" "$stamp"
  dpkg-deb -x "$deb" "$extract/$p" || die "dpkg -x $(basename "$deb") failed"
  echo "$(basename "$deb") $(dpkg-deb -f "$deb" Package) $(dpkg-deb -f "$deb" Version) $(sha256sum "$deb" | cut -d' ' -f1)" >"$stamp"
done

# 3. Collect the TORCS bodies: <name>.acc is the full-detail model (the -lodN files are
#    coarser levels of detail of the same car).
torcs_dir="$extract/torcs-data/usr/share/games/torcs/cars"
[ -d "$torcs_dir" ] || die "'$torcs_dir' missing: torcs-data's layout changed?"
for name in "${torcs_cars[@]}"; do
  collect "$torcs_dir/$name/$name.acc" "$cars/torcs/$name.acc" torcs-data
done

# 4. Collect the Trigger Rally bodies from data.zip (one variant per distinct body).
zip="$extract/trigger-rally-data/usr/share/games/trigger-rally/data.zip"
[ -f "$zip" ] || die "'$zip' missing: trigger-rally-data's layout changed?"
zip_dir="$extract/trigger-rally-vehicles"
zip_stamp="$zip_dir.done"
if [ -f "$zip_stamp" ] && [ -d "$zip_dir/vehicles" ]; then
  say "have Trigger Rally vehicles unzipped"
else
  rm -rf "$zip_dir" "$zip_stamp"
  mkdir -p "$zip_dir"
  say "unzipping vehicles/ from data.zip"
  unzip -q -o "$zip" 'vehicles/*' -d "$zip_dir" || die "unzip of vehicles/ from $zip failed"
  touch "$zip_stamp"
fi
for body in "${trigger_bodies[@]}"; do
  for ext in obj mtl; do
    collect "$zip_dir/vehicles/${body}_wrc/${body}_wrc.$ext" "$cars/trigger/${body}_wrc.$ext" data.zip
  done
done

# 4b. The road cars vendored in the repository (refreshed on every run).
road_src="$root/models/cad/gazebo_models"
[ -d "$road_src" ] || die "'$road_src' missing: the repository's vendored road cars (models/cad/)"
rm -rf "$cars/road.tmp"
mkdir -p "$cars/road.tmp"
cp -r "$road_src" "$cars/road.tmp/gazebo_models" || die "cannot copy $road_src"
rm -rf "$cars/road"
mv "$cars/road.tmp" "$cars/road"

# 5. The manifest beside the cars, and a record of where everything came from.
if [ -f "$manifest_src" ]; then
  cmp -s "$manifest_src" "$cars/cad_manifest.json" || cp "$manifest_src" "$cars/cad_manifest.json"
else
  say "warning: $manifest_src not found; no manifest copied"
fi
{
  echo "# samp CAD cars, collected by tools/get_cad_cars.sh"
  for p in "${packages[@]}"; do
    echo "package $(cut -d' ' -f2- "$extract/$p.done")"
  done
  echo "road cars: models/cad/gazebo_models of the samp repository (CC BY 3.0, (c) 2012 Nathan Koenig, osrf/gazebo_models)"
  (cd "$cars" && sha256sum torcs/*.acc trigger/*.obj trigger/*.mtl && find road -type f | sort | xargs sha256sum)
} >"$cars/SOURCES.txt.tmp"
mv "$cars/SOURCES.txt.tmp" "$cars/SOURCES.txt"

# 6. Report.
count_torcs=$(find "$cars/torcs" -maxdepth 1 -name "*.acc" | wc -l)
count_trigger=$(find "$cars/trigger" -maxdepth 1 -name "*.obj" | wc -l)
count_road=$(find "$cars/road" -path "*/meshes/*" \( -name "*.obj" -o -name "*.dae" \) | wc -l)
say "cars in $cars:"
(cd "$cars" && for f in torcs/*.acc trigger/*.obj; do
  printf '  %-24s %8d bytes\n' "$f" "$(stat -c %s "$f")"
done)
[ "$count_torcs" -eq ${#torcs_cars[@]} ] || die "expected ${#torcs_cars[@]} TORCS cars, found $count_torcs"
[ "$count_trigger" -eq ${#trigger_bodies[@]} ] || die "expected ${#trigger_bodies[@]} Trigger Rally bodies, found $count_trigger"
[ "$count_road" -eq 4 ] || die "expected 4 road cars under $cars/road, found $count_road"
say "got $count_torcs TORCS cars, $count_trigger Trigger Rally bodies and $count_road road cars"
say "train with: samp train $cars --manifest $cars/cad_manifest.json -o MODEL.vdb"
