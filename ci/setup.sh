#!/usr/bin/env bash
# Installs what Tessera needs on a fresh Debian/Ubuntu machine, idempotently:
#   - lavapipe (Mesa's Vulkan driver on the CPU) and the Vulkan loader: the adapter of last resort;
#   - assimp-testmodels: 2CylinderEngine.glb, the vertex-heavy glTF test scene;
# Needs root or sudo for apt-get. Prints what it installed; does nothing when all is present.
set -euo pipefail
cd "$(dirname "$0")/.."

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

need=()
for pkg in mesa-vulkan-drivers libvulkan1 assimp-testmodels; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need+=("$pkg")
done
if [ "${#need[@]}" -gt 0 ]; then
  echo "ci/setup.sh: installing ${need[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi

model=/usr/share/assimp/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb
if [ ! -f "$model" ]; then
  echo "ci/setup.sh: $model is missing after installing assimp-testmodels" >&2
  exit 1
fi
