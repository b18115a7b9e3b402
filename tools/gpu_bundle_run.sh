#!/usr/bin/env bash
# Runs Penumbra's test suite and a quick benchmark from the bundle tools/gpu_bundle.sh makes, on
# a machine with neither Blender nor a network (made for a GPU machine with NVIDIA's driver).
#
#   gpu_bundle_run.sh [--parts DIR] [--dest DIR] [--out DIR] [--check | --unpack-only]
#                     [--no-tests] [--no-bench] [PYTEST_ARG...]
#
#   --parts DIR    the parts and SHA256SUMS (default: this script's folder)
#   --dest DIR     unpack there (default: a new temporary folder); a bundle already unpacked
#                  there from the same archive is reused without its parts
#   --out DIR      results (default: $OUT if set, else ./gpu-results): summary.txt, gl.txt,
#                  pytest.log, failures.txt (each failure's message as it fails: kept when the
#                  time limit kills the run), junit.xml, bench.md, bench.log, perf.csv (each
#                  under 16 MiB)
#   --check        only check the parts' checksums
#   PYTEST_ARG...  narrow the suite (default: $PYTEST_ARGS, else the whole suite), e.g.
#                  gpu_bundle_run.sh tests/core tests/post/test_sepia.py -x
#
# Environment: PYTEST_ARGS, BENCH_ARGS (options of `python -m tools.bench perf`, default
# --quick), TEST_TIMEOUT (seconds, default 420), BENCH_TIMEOUT (default 300), PROBE_TIMEOUT
# (default 120). EGL: NVIDIA's glvnd vendor file when the machine has one, else whatever EGL
# the machine has (Mesa's llvmpipe, for instance).
#
# Exit status: 0 all passed; 1 tests failed or timed out; 2 the benchmark failed or timed out;
# 3 a part is missing or corrupt; 4 the bundle does not start (libraries, Python, GPU context);
# 64 bad usage.
set -euo pipefail

name=penumbra-gpu
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
parts_dir="$here"
dest=""
out="${OUT:-./gpu-results}"
mode=run
run_tests=1
run_bench=1
pytest_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --parts) parts_dir="${2:?--parts needs a folder}"; shift 2 ;;
    --dest) dest="${2:?--dest needs a folder}"; shift 2 ;;
    --out) out="${2:?--out needs a folder}"; shift 2 ;;
    --check) mode=check; shift ;;
    --unpack-only) mode=unpack; shift ;;
    --no-tests) run_tests=0; shift ;;
    --no-bench) run_bench=0; shift ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    --) shift; pytest_args+=("$@"); break ;;
    *) pytest_args+=("$1"); shift ;;
  esac
done
if [ ${#pytest_args[@]} -eq 0 ] && [ -n "${PYTEST_ARGS:-}" ]; then
  read -r -a pytest_args <<< "$PYTEST_ARGS"
fi

say() { echo "gpu_bundle_run: $*"; }
fail() { echo "gpu_bundle_run: $2" >&2; exit "$1"; }
now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }

# --- parts -----------------------------------------------------------------------------------
sums="$parts_dir/SHA256SUMS"
whole_sum=""
[ -f "$sums" ] && whole_sum="$(awk -v n="$name.tar.xz" '$2 == n {print $1}' "$sums")"

check_parts() {
  [ -f "$sums" ] || fail 3 "no SHA256SUMS in $parts_dir (it comes with the parts)"
  [ -n "$whole_sum" ] || fail 3 "SHA256SUMS in $parts_dir names no $name.tar.xz"
  local bad=0 sum part actual n=0
  while read -r sum part; do
    case "$part" in "$name.tar.xz.part-"*) ;; *) continue ;; esac
    n=$((n + 1))
    if [ ! -f "$parts_dir/$part" ]; then
      echo "gpu_bundle_run: MISSING part $part (expected in $parts_dir)" >&2; bad=1; continue
    fi
    actual="$(sha256sum < "$parts_dir/$part" | cut -d' ' -f1)"
    if [ "$actual" != "$sum" ]; then
      echo "gpu_bundle_run: CORRUPT part $part: sha256 $actual, expected $sum" >&2; bad=1
    fi
  done < "$sums"
  [ "$n" -gt 0 ] || fail 3 "SHA256SUMS in $parts_dir lists no part"
  [ "$bad" = 0 ] || fail 3 "parts missing or corrupt in $parts_dir: copy them again"
  for part in "$parts_dir/$name".tar.xz.part-*; do
    [ -e "$part" ] || continue
    grep -q " ${part##*/}\$" "$sums" || say "note: ${part##*/} is not in SHA256SUMS, ignored"
  done
  say "all $n parts present and intact"
}

list_parts() { awk -v p="$name.tar.xz.part-" 'index($2, p) == 1 {print $2}' "$sums" | sort; }

if [ "$mode" = check ]; then check_parts; exit 0; fi

# --- unpack ----------------------------------------------------------------------------------
if [ -z "$dest" ]; then
  dest="$(mktemp -d "${TMPDIR:-/tmp}/penumbra-gpu.XXXXXX")"
fi
mkdir -p "$dest"
dest="$(cd "$dest" && pwd)"
bundle="$dest/$name"
stamp="$bundle/.archive-sha256"
if [ -f "$stamp" ] && { [ -z "$whole_sum" ] || [ "$(cat "$stamp")" = "$whole_sum" ]; }; then
  say "reusing the bundle unpacked in $bundle (archive sha256 $(cat "$stamp"))"
else
  check_parts
  start="$(now)"
  actual="$(cd "$parts_dir" && list_parts | xargs cat | sha256sum | cut -d' ' -f1)"
  [ "$actual" = "$whole_sum" ] || fail 3 "the joined parts have sha256 $actual, expected $whole_sum"
  rm -rf "$bundle"
  if command -v xz >/dev/null 2>&1; then
    unxz=(xz -dc -T0)
  elif command -v python3 >/dev/null 2>&1; then
    unxz=(python3 -c "import lzma, shutil, sys; shutil.copyfileobj(lzma.open(sys.stdin.buffer), sys.stdout.buffer)")
  else
    fail 4 "neither xz nor python3 on PATH to decompress the bundle"
  fi
  (cd "$parts_dir" && list_parts | xargs cat) | "${unxz[@]}" | tar -C "$dest" -xf -
  echo "$whole_sum" > "$stamp"
  say "unpacked into $bundle in $(elapsed "$start") s (checksums, join, xz -d, tar)"
fi
[ -x "$bundle/python/bin/python3.13" ] || fail 4 "$bundle has no python/bin/python3.13"
[ "$mode" = unpack ] && exit 0

# --- environment -----------------------------------------------------------------------------
mkdir -p "$out"
out="$(cd "$out" && pwd)"
rm -f "$out"/{summary.txt,gl.txt,pytest.log,failures.txt,junit.xml,bench.md,bench.log,perf.csv}
py="$bundle/python/bin/python3.13"
export LD_LIBRARY_PATH="$bundle/python/lib:$bundle/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export PATH="$bundle/python/bin:$PATH"
export PYTHONNOUSERSITE=1 PENUMBRA_BUNDLE="$bundle"
unset PYTHONHOME PYTHONPATH PYTHONSTARTUP VIRTUAL_ENV
if [ -n "${__EGL_VENDOR_LIBRARY_FILENAMES:-}" ]; then
  egl="EGL vendor file from the environment: $__EGL_VENDOR_LIBRARY_FILENAMES"
else
  egl="no NVIDIA EGL vendor file (glvnd): falling back to whatever EGL this machine has"
  for f in /usr/share/glvnd/egl_vendor.d/10_nvidia.json \
           /usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json \
           /etc/glvnd/egl_vendor.d/10_nvidia.json; do
    if [ -f "$f" ]; then export __EGL_VENDOR_LIBRARY_FILENAMES="$f"; egl="NVIDIA EGL through glvnd: $f"; break; fi
  done
fi
say "$egl"

limit() {  # keep a result file under 16 MiB: its last 15 MiB
  local f="$1"
  if [ -f "$f" ] && [ "$(stat -c %s "$f")" -gt 15728640 ]; then
    tail -c 15728640 "$f" > "$f.tmp" && mv "$f.tmp" "$f"
  fi
}

# --- GPU probe: what Blender's gpu module draws with, and that Python runs from the bundle ----
probe="$(mktemp "${TMPDIR:-/tmp}/penumbra-gpu-probe.XXXXXX.py")"
cat > "$probe" <<'EOF'
import os
import sys

bundle = os.path.realpath(os.environ["PENUMBRA_BUNDLE"])
print(f"python {sys.version.split()[0]} sys.prefix {sys.prefix} sys.executable {sys.executable}")
inside = all(os.path.realpath(p).startswith(bundle + os.sep) for p in (sys.prefix, sys.executable))
print("python runs from the bundle" if inside else f"ERROR: python does not run from {bundle}")
import bpy  # noqa: E402
import gpu  # noqa: E402

print(f"bpy {bpy.app.version_string} from {os.path.dirname(bpy.__file__)}")
info = {}


class GPU_BUNDLE_PROBE(bpy.types.RenderEngine):
    bl_idname = "GPU_BUNDLE_PROBE"
    bl_label = "GPU bundle probe"
    bl_use_gpu_context = True

    def render(self, depsgraph):
        p = gpu.platform
        info.update(renderer=p.renderer_get(), vendor=p.vendor_get(), version=p.version_get())
        info.update(backend=p.backend_type_get(), device=p.device_type_get())


bpy.utils.register_class(GPU_BUNDLE_PROBE)
scene = bpy.context.scene
scene.render.engine = "GPU_BUNDLE_PROBE"
scene.render.resolution_x = scene.render.resolution_y = 8
bpy.ops.render.render()
for key in ("renderer", "vendor", "version", "backend", "device"):
    print(f"GL {key}: {info.get(key)}")
sys.stdout.flush()
os._exit(0 if inside and info else 1)
EOF
{
  echo "machine: $(uname -srm)"
  echo "$egl"
  command -v nvidia-smi >/dev/null 2>&1 && nvidia-smi -L 2>&1 | head -8
  cache="$(ldconfig -p 2>/dev/null || /sbin/ldconfig -p 2>/dev/null || true)"
  for lib in libEGL.so.1 libGL.so.1 libGLX.so.0 libGLdispatch.so.0; do
    grep -q "^[[:space:]]*$lib " <<< "$cache" || echo "WARNING: $lib is not installed: Blender needs it (glvnd)"
  done
  missing="$(ldd "$bundle/python/lib/python3.13/site-packages/bpy/__init__.so" | awk '$3 == "not" {print $1}')"
  [ -z "$missing" ] || echo "ERROR: bpy needs libraries this machine lacks: $(echo $missing)"
} > "$out/gl.txt" 2>&1
probe_status=0
(cd "$bundle/repo" && timeout -k 10 "${PROBE_TIMEOUT:-120}" "$py" -s "$probe") >> "$out/gl.txt" 2>&1 || probe_status=$?
rm -f "$probe"
grep -E "^(machine|NVIDIA|GPU [0-9]|WARNING|ERROR|python|bpy|GL )" "$out/gl.txt" | sed 's/^/  /' || true
if [ "$probe_status" != 0 ]; then
  tail -n 30 "$out/gl.txt" >&2
  echo "probe: FAILED (status $probe_status)" > "$out/summary.txt"
  fail 4 "the bundle's Python did not get a GPU context in Blender (status $probe_status; see $out/gl.txt)"
fi

# --- test suite and benchmark ----------------------------------------------------------------
status=0
summary=("probe: ok")
describe() {  # the words for a step's exit status
  case "$1" in 0) echo ok ;; 124|137) echo "TIMED OUT after $2 s" ;; *) echo "FAILED (status $1)" ;; esac
}
if [ "$run_tests" = 1 ]; then
  t="${TEST_TIMEOUT:-420}"
  say "pytest -q ${pytest_args[*]:-tests} (timeout ${t} s)"
  start="$(now)"
  rc=0
  (cd "$bundle/repo" && PENUMBRA_FAILURES="$out/failures.txt" timeout -k 15 "$t" "$py" -s -m pytest -q \
    --junitxml="$out/junit.xml" "${pytest_args[@]:-tests}") > "$out/pytest.log" 2>&1 || rc=$?
  limit "$out/pytest.log"; limit "$out/junit.xml"; limit "$out/failures.txt"
  tail -n 25 "$out/pytest.log"
  failed="$(grep -c '^FAILED ' "$out/failures.txt" 2>/dev/null || true)"
  summary+=("tests: $(describe "$rc" "$t") in $(elapsed "$start") s: $(grep -E '^[=]* *[0-9]+ (passed|failed)|^[=]* *[0-9]+ .* in [0-9.]+s' "$out/pytest.log" | tail -1 | tr -d '=' || true); ${failed:-0} failure(s) in failures.txt")
  [ "$rc" = 0 ] || status=1
fi
if [ "$run_bench" = 1 ]; then
  t="${BENCH_TIMEOUT:-300}"
  read -r -a bench_args <<< "${BENCH_ARGS:---quick}"
  bench_out="$(mktemp -d "${TMPDIR:-/tmp}/penumbra-gpu-bench.XXXXXX")"
  say "python -m tools.bench perf ${bench_args[*]} (timeout ${t} s)"
  start="$(now)"
  rc=0
  (cd "$bundle/repo" && timeout -k 15 "$t" "$py" -s -m tools.bench perf --out "$bench_out" "${bench_args[@]}") \
    > "$out/bench.md" 2> "$out/bench.log" || rc=$?
  [ -f "$bench_out/perf.csv" ] && cp "$bench_out/perf.csv" "$out/perf.csv"
  rm -rf "$bench_out"
  limit "$out/bench.md"; limit "$out/bench.log"; limit "$out/perf.csv"
  tail -n 15 "$out/bench.log" >&2
  cat "$out/bench.md"
  summary+=("bench: $(describe "$rc" "$t") in $(elapsed "$start") s")
  [ "$rc" = 0 ] || [ "$status" != 0 ] || status=2
fi
printf '%s\n' "$egl" "${summary[@]}" > "$out/summary.txt"
say "results in $out:"
ls -l "$out" | tail -n +2 | sed 's/^/  /'
sed 's/^/  /' "$out/summary.txt"
exit "$status"
