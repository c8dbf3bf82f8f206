#!/usr/bin/env bash
# The real COLMAP program on a clayfit synth capture (16 images, 640 x 480):
# feature extraction and matching on the CPU, then the mapper, with the
# camera calibrated (COLMAP is given the pinhole intrinsics and keeps them,
# as for a user's calibrated camera); then the checker compares COLMAP's
# camera centres with the true orbit.
# usage: colmap_reconstruction.sh CLAYFIT CHECKER WORK_DIR
# Exit 77 (skipped) when colmap is not installed.
set -euo pipefail
clayfit=$1 checker=$2 work=$3
if ! command -v colmap >/dev/null; then
  echo "colmap is not installed: skipped"
  exit 77
fi
export QT_QPA_PLATFORM=offscreen
rm -rf "$work"
"$clayfit" --quiet synth -o "$work" --images 16 --size 640x480
cd "$work"
start=$(date +%s)
colmap feature_extractor --database_path db.db --image_path images \
  --ImageReader.single_camera 1 --ImageReader.camera_model PINHOLE \
  --ImageReader.camera_params 768,768,320,240 \
  --SiftExtraction.use_gpu 0 --SiftExtraction.max_num_features 1500 > extract.log 2>&1
# the orbit is ordered, so neighbours suffice (half the pairs of exhaustive)
colmap sequential_matcher --database_path db.db --SiftMatching.use_gpu 0 \
  --SequentialMatching.overlap 5 --SequentialMatching.quadratic_overlap 0 > match.log 2>&1
mkdir -p colmap
# most matches are on the backdrop, far away: start from a smaller angle
colmap mapper --database_path db.db --image_path images --output_path colmap \
  --Mapper.init_min_tri_angle 4 --Mapper.init_min_num_inliers 50 \
  --Mapper.ba_refine_focal_length 0 --Mapper.ba_refine_extra_params 0 > mapper.log 2>&1
echo "colmap: extraction, matching and mapping took $(( $(date +%s) - start )) s"
"$checker" sparse/0 colmap/0
