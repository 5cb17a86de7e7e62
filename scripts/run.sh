#!/usr/bin/env bash
# The main job: build purkinje (Release), render the bundled scenes
# (sensor image PNG, EXR with radiance and AOVs, labels JSON) and write
# their ground-truth labels as JSON and CSV, into out/<scene>/; then a
# small labelled set of each bundled dataset spec (out/<scene>_set/: 20
# images, their segmentations and labels, and table.csv).
set -euo pipefail
cd "$(dirname "$0")/.."
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"  # cache hits across checkouts

bash scripts/install-deps.sh
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build/release --target purkinje purkinje_python_package

for scene in remote headset remote_face; do
  mkdir -p "out/$scene"
  build/release/tools/purkinje render "assets/scenes/$scene.json" -o "out/$scene"
  build/release/tools/purkinje truth "assets/scenes/$scene.json" -o "out/$scene/labels.json"
  build/release/tools/purkinje truth "assets/scenes/$scene.json" -o "out/$scene/labels.csv"
done
for spec in remote headset; do
  build/release/tools/purkinje generate "assets/datasets/$spec.json" -o "out/${spec}_set" --count 20
done

echo
echo "Images and labels written (open the .png files in any viewer; the .exr"
echo "files hold float radiance and AOVs; docs/rendering.md explains them):"
ls -l out/remote out/headset out/remote_face
echo
echo "Labelled sets (docs/datasets.md): out/remote_set, out/headset_set, each with table.csv"
echo
echo "Python (docs/python.md): export PYTHONPATH=$PWD/build/release/python, then import purkinje"
