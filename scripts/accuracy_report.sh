#!/usr/bin/env bash
# The accuracy-cost report (issue 11): blender_tests/accuracy_report.py in Debian's Blender under
# Xvfb (the GPU frame times and previews need a GPU context), then scripts/accuracy_summary.py
# (the Markdown summary, plots and image strip, with /usr/bin/python3's matplotlib).
#   bash scripts/accuracy_report.sh [OUT] [--quick] [--scenes sphere,bowl]
# OUT defaults to docs/report (the committed full run); needs build/sd_lighting.zip
# (scripts/build.sh). Blender's user folders and the images behind the strip go to
# build/accuracy_report_work. Exits with the report's status (non-zero when an invariant fails).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=$root/docs/report
if (( $# )) && [[ $1 != --* ]]; then out=$(realpath -m "$1"); shift; fi
zip=$root/build/sd_lighting.zip
[ -f "$zip" ] || { echo "accuracy_report.sh: $zip not found: build first (scripts/build.sh)" >&2; exit 2; }
work=$root/build/accuracy_report_work
user=$work/blender_user
rm -rf "$user"
mkdir -p "$user" "$out"
start=$(date +%s)
status=0
# FLIP's tools venv stays where bpy_modules.py installs it, not under the redirected cache
bpy_cache=$(/usr/bin/python3 -c 'import sys; sys.path.insert(0, sys.argv[1]); import bpy_modules; print(bpy_modules.cache_directory())' "$root/blender_tests")
SD_BPY_CACHE=$bpy_cache BLENDER_USER_SCRIPTS=$user/scripts BLENDER_USER_CONFIG=$user/config XDG_CACHE_HOME=$user/cache \
  xvfb-run -a -s "-screen 0 1280x1024x24" blender --factory-startup --python-exit-code 1 \
  --python "$root/blender_tests/accuracy_report.py" -- --zip "$zip" --out "$out" --work "$work" "$@" \
  || status=$?
/usr/bin/python3 "$root/scripts/accuracy_summary.py" "$out" "$work"
echo "accuracy report: $(( $(date +%s) - start )) s in all, exit $status: $out/report.md"
exit $status
