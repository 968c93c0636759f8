#!/usr/bin/env bash
# Draws the README's picture: the README's own play command, with --plot.
#
# Usage: scripts/readme_picture.sh [OUT.png]   (default: docs/arm-wave.png)
#
# It plays configs/motions/arm-wave.yaml on the built-in simulated SO-101
# arm in real time, as the README's "Two commands" do, and draws the
# planned against the measured positions and the tracking error into the
# PNG. Run it from anywhere; paths are from the repository's root. It
# fails when the run fails or the file written is not a PNG.
set -euo pipefail
cd "$(dirname "$0")/.."

out=${1:-docs/arm-wave.png}
case $out in
*.png) ;;
*)
    echo "readme_picture.sh: $out: the picture is a .png" >&2
    exit 2
    ;;
esac

cargo run --release -- play configs/motions/arm-wave.yaml --plot "$out"

# A PNG starts with the 8 bytes 89 50 4E 47 0D 0A 1A 0A.
magic=$(head -c 8 "$out" | od -An -tx1 | tr -d ' \n')
if [ "$magic" != 89504e470d0a1a0a ]; then
    echo "readme_picture.sh: $out is not a PNG (it starts with $magic)" >&2
    exit 1
fi
echo "wrote $out ($(wc -c <"$out") bytes, PNG)"
