#!/usr/bin/env bash
# Packs everything the test suite and the benchmarks need into a bundle for a GPU machine that
# has neither Blender nor a network: a relocatable CPython 3.13 (the interpreter of
# .venv/blender-5.2), that venv's site-packages (bpy, numpy, OpenImageIO, pytest, ...) without
# the bpy wheel's GPU kernels for Cycles, the shared libraries they need that a minimal machine
# may lack (X11 client libraries, libssl, libffi, ...; never glibc, libstdc++, OpenGL/EGL or
# Mesa: the GPU machine's own driver draws), and the project at HEAD (git archive).
#
#   tools/gpu_bundle.sh [OUT_DIR]        # default out/gpu-bundle
#   tools/gpu_bundle.sh --list-excludes  # the kernel files left out, pattern by pattern
#
# OUT_DIR then holds penumbra-gpu.tar.xz.part-NN (at most PART_SIZE each), SHA256SUMS (every
# part and the whole archive) and gpu_bundle_run.sh, the runner (see its header).
# Environment: PART_SIZE (split's -b, default 56m), XZ_OPT_LEVEL (default 6),
# KEEP_CUDA=1 (keep Cycles' CUDA/OptiX kernels and OIDN's CUDA device).
set -euo pipefail
cd "$(dirname "$0")/.."

line=5.2
py_minor=3.13
venv=".venv/blender-$line"
name=penumbra-gpu
part_size="${PART_SIZE:-56m}"
xz_level="${XZ_OPT_LEVEL:-6}"

# Files of the venv's site-packages left out, as find -path patterns relative to it. Penumbra
# draws through OpenGL and never runs Cycles on a GPU; Cycles on the CPU keeps working.
# bpy/__init__.so links libcycles_kernel_oneapi_aot.so (oneAPI kernels, 38 MiB that xz cannot
# shrink): it is replaced by a stub of its six entry points, each failing as "no kernels".
KERNEL_EXCLUDES=(
  "bpy/*/scripts/addons_core/cycles/lib/kernel_*.fatbin.zst"  # AMD HIP
  "bpy/*/scripts/addons_core/cycles/lib/kernel_rt_*.hipfb.zst" # AMD HIP RT
  "bpy/lib/libOpenImageDenoise_device_hip.so*"                # OIDN on AMD
  "bpy/lib/libOpenImageDenoise_device_sycl.so*"               # OIDN on Intel
  "bpy/lib/libcycles_kernel_oneapi_aot.so"                    # Intel oneAPI (stubbed)
)
CUDA_EXCLUDES=(
  "bpy/*/scripts/addons_core/cycles/lib/kernel_*.cubin.zst"   # NVIDIA CUDA
  "bpy/*/scripts/addons_core/cycles/lib/kernel_*.ptx.zst"     # NVIDIA CUDA/OptiX PTX
  "bpy/lib/libOpenImageDenoise_device_cuda.so*"               # OIDN on NVIDIA
)
excludes=("${KERNEL_EXCLUDES[@]}")
[ "${KEEP_CUDA:-0}" = 1 ] || excludes+=("${CUDA_EXCLUDES[@]}")
ONEAPI_STUB="bpy/lib/libcycles_kernel_oneapi_aot.so"

# Shared libraries never copied into the bundle: glibc, the C++ runtime (the GPU machine's own,
# as for a pip-installed bpy), and OpenGL/EGL/GBM/DRM/Vulkan/Mesa/NVIDIA (the machine's driver).
SYSTEM_LIBS='^(ld-linux-x86-64|libc|libm|libmvec|libdl|libpthread|librt|libutil|libresolv|libnsl|libanl|libthread_db|libBrokenLocale|libstdc\+\+|libgcc_s|libGL|libEGL|libGLX|libGLdispatch|libOpenGL|libGLESv1_CM|libGLESv2|libgbm|libglapi|libdrm|libdrm_[a-z0-9]+|libvulkan|libgallium.*|libLLVM.*|libnvidia-.*|libcuda)\.so'

# X11 client libraries bpy links (directly or through its libraries), by Debian package.
X11_LIBS="libX11.so.6:libx11-6 libXext.so.6:libxext6 libXrender.so.1:libxrender1 libXfixes.so.3:libxfixes3
libXi.so.6:libxi6 libxkbcommon.so.0:libxkbcommon0 libSM.so.6:libsm6 libICE.so.6:libice6 libXt.so.6:libxt6"

die() { echo "gpu_bundle: $*" >&2; exit 1; }

site_packages() {
  local sp
  sp="$(ls -d "$venv"/lib/python"$py_minor"/site-packages 2>/dev/null || true)"
  [ -n "$sp" ] && [ -d "$sp/bpy" ] || die "$venv has no bpy: run tools/setup.sh $line first"
  echo "$sp"
}

# Every file of $1 matched by the exclusion patterns, "pattern<TAB>path" per line.
list_excludes() {
  local sp="$1" p f
  for p in "${excludes[@]}"; do
    while IFS= read -r f; do printf '%s\t%s\n' "$p" "${f#"$sp"/}"; done < <(find "$sp" -path "$sp/$p" -type f | sort)
  done
}

if [ "${1:-}" = --list-excludes ]; then
  sp="$(site_packages)"
  listing="$(list_excludes "$sp")"
  status=0
  for p in "${excludes[@]}"; do
    n="$(printf '%s\n' "$listing" | awk -F'\t' -v p="$p" '$1 == p' | grep -c . || true)"
    [ "$n" -gt 0 ] || { echo "gpu_bundle: pattern matches nothing: $p" >&2; status=1; }
  done
  printf '%s\n' "$listing"
  exit $status
fi

out="${1:-out/gpu-bundle}"
case "$out" in -*) die "unknown option '$out' (use: tools/gpu_bundle.sh [OUT_DIR] | --list-excludes)" ;; esac
for tool in git xz tar split sha256sum ldd find; do
  command -v "$tool" >/dev/null 2>&1 || die "needs '$tool' on PATH"
done
sp="$(site_packages)"

# --- X11 client libraries --------------------------------------------------------------------
missing_pkgs=""
cache="$(ldconfig -p 2>/dev/null || /sbin/ldconfig -p 2>/dev/null || true)"
for entry in $X11_LIBS; do
  lib="${entry%%:*}" pkg="${entry#*:}"
  grep -q "^[[:space:]]*$lib " <<< "$cache" || missing_pkgs="$missing_pkgs $pkg"
done
if [ -n "$missing_pkgs" ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "gpu_bundle: installing X11 client libraries:$missing_pkgs"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $missing_pkgs >/dev/null
  else
    echo "gpu_bundle: the bundle carries X11 client libraries this machine lacks:$missing_pkgs" >&2
    die "install them as root: apt-get install$missing_pkgs"
  fi
fi

# --- Python ----------------------------------------------------------------------------------
# The interpreter the venv was made with (pyvenv.cfg), else as tools/setup.sh finds one.
python=""
home="$(sed -n 's/^home = //p' "$venv/pyvenv.cfg" 2>/dev/null || true)"
[ -n "$home" ] && [ -x "$home/python$py_minor" ] && python="$home/python$py_minor"
if [ -z "$python" ]; then
  root="${PYENV_ROOT:-$HOME/.pyenv}"
  for c in $(command -v "python$py_minor" 2>/dev/null) \
           $(ls -d "$root"/versions/"$py_minor"* 2>/dev/null | sort -V -r | sed "s|\$|/bin/python$py_minor|"); do
    if [ -x "$c" ] && "$c" -c "import sys; assert sys.version_info[:2] == (3, 13)" 2>/dev/null; then
      python="$c"; break
    fi
  done
fi
[ -n "$python" ] || die "no Python $py_minor found (pyvenv.cfg of $venv, PATH or pyenv)"
read -r prefix libdir ldlibrary < <("$python" -c "import sys, sysconfig as s
print(sys.base_prefix, s.get_config_var('LIBDIR'), s.get_config_var('LDLIBRARY'))")
stdlib="$prefix/lib/python$py_minor"
[ -f "$stdlib/os.py" ] || die "$python: no standard library at $stdlib"

stage_root="$(mktemp -d "${TMPDIR:-/tmp}/penumbra-gpu-bundle.XXXXXX")"
trap 'rm -rf "$stage_root"' EXIT
stage="$stage_root/$name"
mkdir -p "$stage/python/bin" "$stage/python/lib" "$stage/lib" "$stage/repo"
echo "gpu_bundle: python $("$python" --version 2>&1) from $prefix"

cp -L "$python" "$stage/python/bin/python$py_minor"
ln -s "python$py_minor" "$stage/python/bin/python3"
ln -s "python$py_minor" "$stage/python/bin/python"
if [[ "$ldlibrary" == *.so* ]]; then  # a shared libpython
  cp -L "$libdir/$ldlibrary" "$stage/python/lib/"
  so="$(readelf -d "$libdir/$ldlibrary" | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p')"
  [ -z "$so" ] || [ -e "$stage/python/lib/$so" ] || cp -L "$libdir/$so" "$stage/python/lib/"
fi
# The standard library without its tests, Tk, IDLE and static libraries.
tar -C "$prefix/lib" -cf - \
  --exclude="python$py_minor/site-packages" --exclude="python$py_minor/test" \
  --exclude="python$py_minor/idlelib" --exclude="python$py_minor/tkinter" \
  --exclude="python$py_minor/turtledemo" --exclude="python$py_minor/ensurepip" \
  --exclude="python$py_minor/lib-dynload/_tkinter*" --exclude='*.a' \
  "python$py_minor" | tar -C "$stage/python/lib" -xf -

# --- site-packages ---------------------------------------------------------------------------
dest_sp="$stage/python/lib/python$py_minor/site-packages"
mkdir -p "$dest_sp"
list_excludes "$sp" | cut -f2 | sed 's|^|./|' > "$stage_root/excludes"
[ -s "$stage_root/excludes" ] || die "no kernel file of $sp matches the exclusion list: is bpy $line installed?"
dropped="$(sed 's|^\./||' "$stage_root/excludes" | (cd "$sp" && xargs -d '\n' du -cb) | tail -1 | cut -f1)"
tar -C "$sp" -cf - --exclude-from="$stage_root/excludes" --exclude='./pip' --exclude='./pip-*' . \
  | tar -C "$dest_sp" -xf -
echo "gpu_bundle: left out $(wc -l < "$stage_root/excludes") kernel files, $((dropped / 1048576)) MiB"

# The stub: bpy/__init__.so links the oneAPI library, which only Cycles on an Intel GPU calls.
if [ -f "$sp/$ONEAPI_STUB" ] && [ ! -f "$dest_sp/$ONEAPI_STUB" ]; then
  command -v cc >/dev/null 2>&1 || die "needs a C compiler (cc) for the stub of $ONEAPI_STUB"
  cat > "$stage_root/oneapi_stub.c" <<'EOF'
/* Stand-in for Cycles' oneAPI kernel library in the GPU bundle: no oneAPI kernels. Every entry
   point returns 0 (false, size 0) whatever its arguments (x86-64: the result is in rax). */
long oneapi_stub_none(void) { return 0; }
#define STUB(name) long name(void) __attribute__((alias("oneapi_stub_none")));
STUB(oneapi_set_error_cb)
STUB(oneapi_run_test_kernel)
STUB(oneapi_suggested_gpu_kernel_size)
STUB(oneapi_zero_memory_on_device)
STUB(oneapi_load_kernels)
STUB(oneapi_enqueue_kernel)
EOF
  cc -shared -fPIC -O2 -o "$dest_sp/$ONEAPI_STUB" "$stage_root/oneapi_stub.c"
  wanted="$(nm -D --defined-only "$sp/$ONEAPI_STUB" | awk '$2 == "T" {print $3}' | sort)"
  have="$(nm -D --defined-only "$dest_sp/$ONEAPI_STUB" | awk '$2 == "T" {print $3}' | sort)"
  [ -z "$(comm -23 <(echo "$wanted") <(echo "$have"))" ] \
    || die "the oneAPI stub lacks: $(comm -23 <(echo "$wanted") <(echo "$have") | tr '\n' ' ')"
fi

# Console scripts the tests call next to sys.executable (devkit/farm.py: openjd), relocatable.
for script in openjd:openjd.cli pytest:pytest; do
  cmd="${script%%:*}" module="${script#*:}"
  cat > "$stage/python/bin/$cmd" <<EOF
#!/bin/sh
# $cmd of the GPU bundle's Python (no absolute paths).
here="\$(cd "\$(dirname "\$0")" && pwd)"
LD_LIBRARY_PATH="\$here/../lib:\$here/../../lib\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}" exec "\$here/python$py_minor" -s -c 'import sys; from $module import main; sys.argv[0] = "$cmd"; sys.exit(main())' "\$@"
EOF
  chmod 755 "$stage/python/bin/$cmd"
done

# --- the project -----------------------------------------------------------------------------
git archive HEAD | tar -C "$stage/repo" -xf -
commit="$(git rev-parse HEAD)"
[ -z "$(git status --porcelain --untracked-files=no)" ] \
  || echo "gpu_bundle: note: uncommitted changes are not in the bundle (it holds HEAD, $commit)"

# --- shared libraries ------------------------------------------------------------------------
# Every library an ELF file of the bundle resolves outside it, except the system's own.
find "$stage" -type f \( -name '*.so' -o -name '*.so.*' -o -path "*/bin/python$py_minor" \) > "$stage_root/elves"
: > "$stage_root/deps"
while IFS= read -r f; do
  LD_LIBRARY_PATH="$stage/python/lib" ldd "$f" 2>/dev/null | awk '$2 == "=>" {print $1 "\t" $3}' >> "$stage_root/deps" || true
done < "$stage_root/elves"
copied=""
while IFS=$'\t' read -r soname path; do
  case "$path" in "$stage"/*|not) continue ;; esac
  [[ "$soname" =~ $SYSTEM_LIBS ]] && continue
  [ -e "$stage/lib/$soname" ] && continue
  cp -L "$path" "$stage/lib/$soname"
  copied="$copied $soname"
done < <(sort -u "$stage_root/deps")
echo "gpu_bundle: private libraries:$copied"
# Names that stay unresolved are not on this machine either (bpy's MaterialX Python modules name
# libraries the wheel does not ship): a note, as with the venv itself.
unresolved="$(while IFS= read -r f; do
  LD_LIBRARY_PATH="$stage/python/lib:$stage/lib" ldd "$f" 2>/dev/null | awk '$3 == "not" {print $1}'
done < "$stage_root/elves" | sort -u | while read -r so; do
  [ -n "$(find "$stage" -name "$so" -print -quit)" ] || echo "$so"
done)"
[ -z "$unresolved" ] || echo "gpu_bundle: note: unresolved here as in $venv: $(echo $unresolved)"

cp tools/gpu_bundle_run.sh "$stage/gpu_bundle_run.sh"
cat > "$stage/BUNDLE_INFO" <<EOF
Penumbra GPU bundle
commit $commit
python $("$python" --version 2>&1) ($prefix)
bpy $(sed -n 's/^Version: //p' "$sp"/bpy-*.dist-info/METADATA)
kernels left out: ${excludes[*]}
private libraries:$copied
made $(date -u +%Y-%m-%dT%H:%M:%SZ) on $(uname -m)
EOF

# --- archive, parts, checksums ---------------------------------------------------------------
mkdir -p "$out"
rm -f "$out/$name".tar.xz* "$out/SHA256SUMS" "$out/gpu_bundle_run.sh"
echo "gpu_bundle: compressing $(du -sm "$stage" | cut -f1) MiB (xz -$xz_level -T2)"
start=$(date +%s)
tar -C "$stage_root" --owner=0 --group=0 -cf - "$name" | xz -T2 "-$xz_level" > "$out/$name.tar.xz"
echo "gpu_bundle: compressed in $(($(date +%s) - start)) s"
(
  cd "$out"
  whole="$(sha256sum "$name.tar.xz")"
  split -b "$part_size" -d -a 2 "$name.tar.xz" "$name.tar.xz.part-"
  rm "$name.tar.xz"
  { sha256sum "$name".tar.xz.part-*; echo "$whole"; } > SHA256SUMS
)
cp tools/gpu_bundle_run.sh "$out/gpu_bundle_run.sh"
chmod 755 "$out/gpu_bundle_run.sh"
total="$(cat "$out/$name".tar.xz.part-* | wc -c)"
parts="$(ls "$out/$name".tar.xz.part-* | wc -l)"
echo "gpu_bundle: $out: $parts parts, $((total / 1048576)) MiB in all ($total bytes)"
ls -l "$out"
