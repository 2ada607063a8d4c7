#!/usr/bin/env bash
# Unpacks a lavapipe with hardware ray queries (Mesa 25 from Debian bookworm-backports) into
# DEST, beside the system's Mesa, without installing it: only processes started with
#   VK_DRIVER_FILES=DEST/lvp_icd.json LD_LIBRARY_PATH=DEST/usr/lib/x86_64-linux-gnu
# use it. The ray-query test (crates/refract-cli/tests/ray_query.rs) finds it through
# REFRACT_RAY_QUERY_ICD=DEST/lvp_icd.json. Needs apt-get and dpkg (Debian 12, x86_64); nothing
# outside DEST (and its download cache) is touched.
#
# Usage: scripts/newer-lavapipe.sh DEST
set -euo pipefail
dest="${1:?usage: scripts/newer-lavapipe.sh DEST}"
mkdir -p "$dest"
dest="$(cd "$dest" && pwd)"
apt_dir="$dest/apt"
mkdir -p "$apt_dir/lists/partial" "$apt_dir/debs"
echo "deb http://deb.debian.org/debian bookworm-backports main" >"$apt_dir/sources.list"
apt_options=(
    -o "Dir::Etc::sourcelist=$apt_dir/sources.list"
    -o "Dir::Etc::sourceparts=-"
    -o "Dir::State::Lists=$apt_dir/lists"
    -o "APT::Get::List-Cleanup=0"
)
apt-get "${apt_options[@]}" update >/dev/null
# Mesa's Vulkan drivers and the newer libdrm they link against; everything else they need
# (LLVM 15, libvulkan1, X and Wayland client libraries) is the system's.
(cd "$apt_dir/debs" &&
    apt-get "${apt_options[@]}" download \
        mesa-vulkan-drivers/bookworm-backports libdrm2/bookworm-backports \
        libdrm-amdgpu1/bookworm-backports 2>/dev/null)
for deb in "$apt_dir"/debs/*.deb; do
    dpkg-deb -x "$deb" "$dest"
done
lib="$dest/usr/lib/x86_64-linux-gnu"
test -f "$lib/libvulkan_lvp.so"
cat >"$dest/lvp_icd.json" <<JSON
{ "file_format_version": "1.0.0", "ICD": { "api_version": "1.4.305", "library_path": "$lib/libvulkan_lvp.so" } }
JSON
echo "$dest/lvp_icd.json"
