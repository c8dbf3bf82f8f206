#!/usr/bin/env bash
# Installs the Debian 12 packages clayfit needs, only those not installed:
#   scripts/install-deps.sh demo   what the demo builds and runs with: the
#                                  compiler, CMake and the libraries clayfit
#                                  links (scripts/demo.sh)
#   scripts/install-deps.sh [test] those, and everything the tests use
#                                  (scripts/test.sh), npm packages included
# Runs as root, or through sudo when available.
set -euo pipefail

kind=${1:-test}
case "$kind" in
  demo|test) ;;
  *) echo "usage: scripts/install-deps.sh [demo|test]" >&2; exit 2 ;;
esac

# The demo's: what `scripts/build.sh demo` compiles and links, nothing more.
packages=(
  g++ make cmake pkg-config          # compiler, build
  libjansson-dev                     # JSON (CLI output, capture files)
  libceres-dev                       # fitting (and ceres::Jet in the tests)
  libpng-dev libjpeg62-turbo-dev     # PNG and JPEG read and written (src/capture/image_png.c, image_jpeg.c)
  libopenexr-dev                     # OpenEXR read and written (src/capture/image_exr.cpp)
  libopencv-core-dev libopencv-imgproc-dev  # image analysis (sphere detection; cmake/FindOpenCV.cmake)
  libxxhash-dev                      # XXH3-128: clayfit batch's entry keys
)
# The tests' (and the benchmarks'): every real component a test runs.
test_packages=(
  libopenimageio-dev                 # OpenImageIO: every other format (TIFF, HDR, ...; the module libclayfit_oiio.so) and the codecs' reference in their tests
  openimageio-tools                  # oiiotool: images made and compared in the tests and scripts
  libopencv-imgcodecs-dev            # the DiLiGenT mask read in test_sphere_diligent
  colmap                             # camera poses (integration tests)
  python3 python3-jsonschema         # test harness: JSON Schema validation
  python3-numpy python3-scipy        # the SciPy peer (scripts/peer_scipy.py, bench_peers.sh)
  clang libclang-rt-14-dev           # libFuzzer for the fuzz targets (scripts/fuzz.sh)
  chromium                           # the report's page tested in a real browser
  libxml2-utils                      # xmllint: the MaterialX and Mitsuba presets' tests
  glslang-tools                      # glslangValidator: the GLSL and Unity (HLSL) shader presets' tests
  blender                            # Blender 3.4: the Blender preset rendered (tests/export/blender.cmake)
  slurm-wlm munge                    # the tests' private Slurm cluster (scripts/slurm-local.sh)
)
if [ "$kind" = test ]; then
  packages+=("${test_packages[@]}")
fi
# Node.js and npm for the Khronos glTF validator (npm gltf-validator), from
# Debian unless a node and an npm are already there (another Node.js, such
# as NodeSource's, bundles npm and conflicts with Debian's npm package).
if [ "$kind" = test ]; then
  command -v node >/dev/null || packages+=(nodejs)
  command -v npm >/dev/null || packages+=(npm)
fi

# The Khronos glTF validator for the glTF preset's tests, from the npm
# registry into the project's build/tools/node_modules (tests/export), only
# when missing.
gltf_validator_version=2.0.0-dev.3.10
install_gltf_validator() {
  local root tools
  root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
  tools="$root/build/tools"
  if [ -f "$tools/node_modules/gltf-validator/package.json" ]; then
    echo "install-deps: gltf-validator present in $tools/node_modules"
    return 0
  fi
  npm view "gltf-validator@$gltf_validator_version" version >/dev/null \
    || { echo "install-deps: npm has no gltf-validator@$gltf_validator_version" >&2; return 1; }
  mkdir -p "$tools"
  npm install --no-audit --no-fund --prefix "$tools" "gltf-validator@$gltf_validator_version"
}

# three.js and esbuild for the three.js shader test (tests/export, docs/shaders.md):
# three renders the exported ShaderMaterial in headless Chromium, esbuild bundles
# it into a classic script (Chromium refuses ES modules from file://).
three_version=0.187.0
esbuild_version=0.28.2
install_three() {
  local root tools
  root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
  tools="$root/build/tools"
  if [ -f "$tools/node_modules/three/package.json" ] && [ -x "$tools/node_modules/.bin/esbuild" ]; then
    echo "install-deps: three and esbuild present in $tools/node_modules"
    return 0
  fi
  mkdir -p "$tools"
  npm install --no-audit --no-fund --prefix "$tools" "three@$three_version" "esbuild@$esbuild_version"
}

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
install_npm_packages() {
  if [ "$kind" = test ]; then
    install_gltf_validator
    install_three
  fi
}
if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present ($kind)"
  install_npm_packages
  exit 0
fi

sudo=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo=(sudo)
fi
echo "install-deps: installing ${missing[*]}"
# munge, slurmctld and slurmd are services: their packages start them. The
# tests run their own (scripts/slurm-local.sh), so system ones are not
# wanted; a policy-rc.d that denies every start is put in place while apt
# runs, unless the machine has one (Debian's container images do).
policy=/usr/sbin/policy-rc.d
if [[ " ${missing[*]} " =~ \ (munge|slurm-wlm)\  ]] && [ ! -e "$policy" ]; then
  trap '"${sudo[@]}" rm -f "$policy"' EXIT
  printf '#!/bin/sh\n# install-deps.sh: no service starts while it installs\nexit 101\n' \
    | "${sudo[@]}" tee "$policy" >/dev/null
  "${sudo[@]}" chmod 755 "$policy"
fi
"${sudo[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
install_npm_packages
