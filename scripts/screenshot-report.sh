#!/usr/bin/env bash
# Renders a comparison's index.html in headless Chromium (Debian package `chromium`) and saves a
# full-page PNG, to look at the report as a reader would:
#   scripts/screenshot-report.sh [out/index.html] [out/report-screenshot.png] [height]
set -euo pipefail
html=$(realpath "${1:-out/index.html}")
png=${2:-$(dirname "$html")/report-screenshot.png}
height=${3:-2400}
if ! command -v chromium >/dev/null; then
    echo "chromium not found: apt-get install -y chromium" >&2
    exit 1
fi
profile=$(mktemp -d)
trap 'rm -rf "$profile"' EXIT
chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
    --disable-background-networking --disable-component-update --disable-sync \
    --user-data-dir="$profile" --hide-scrollbars --window-size=1600,"$height" \
    --screenshot="$(realpath -m "$png")" "file://$html" 2>/dev/null
echo "wrote $png"
