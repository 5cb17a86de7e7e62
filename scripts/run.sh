#!/usr/bin/env bash
# The main job: build purkinje (Release) and write ground-truth labels
# (JSON and CSV) for the bundled scenes into out/<scene>/.
set -euo pipefail
cd "$(dirname "$0")/.."
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"  # cache hits across checkouts

bash scripts/install-deps.sh
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build/release --target purkinje

for scene in remote headset; do
  mkdir -p "out/$scene"
  build/release/tools/purkinje truth "assets/scenes/$scene.json" -o "out/$scene/labels.json"
  build/release/tools/purkinje truth "assets/scenes/$scene.json" -o "out/$scene/labels.csv"
done

echo
echo "Labels written:"
ls -l out/remote/labels.json out/remote/labels.csv out/headset/labels.json out/headset/labels.csv
