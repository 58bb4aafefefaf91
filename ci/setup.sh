#!/usr/bin/env bash
# Installs, only when missing, the Debian packages the project needs:
# Vulkan loader + lavapipe + Khronos validation layer, and the static
# shaderc/glslang/SPIRV-Tools archives that `.cargo/config.toml` links
# (Debian's shared libshaderc is unusable: see README "Shaders").
# Idempotent: a second run does nothing and prints nothing.
set -euo pipefail

packages=(
  libvulkan1              # Vulkan loader (ash loads it at run time)
  mesa-vulkan-drivers     # lavapipe, the default device
  vulkan-validationlayers # VK_LAYER_KHRONOS_validation, on in tests
  libshaderc-dev          # libshaderc_combined.a
  glslang-dev             # static glslang archives shaderc_combined needs
  spirv-tools             # libSPIRV-Tools*.a
  g++                     # nv-flip-sys builds NVIDIA's FLIP (C++) for engine eval
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "ci/setup.sh: installing ${missing[*]}" >&2
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
