#pragma once
// Global bundle adjustment of a saved map (`crowdslam map optimise`): load the map file, optimise every
// keyframe pose and map point against all their observations (loop::GlobalBundleAdjuster: Huber loss, the
// first keyframe fixed), save the result as a new map file. The map's camera, settings identity and origin
// are kept; the observations themselves are not changed (none is erased).
//
// Use it to refine a map before reusing it (--load-map), or to ask what the map's measurements alone say:
// the optimum of the reprojection error over the whole map, independent of the order and the windows in
// which local mapping optimised it (docs/MAPPING.md "How to measure" uses it that way). With --ground, the
// global BA a monocular run on a car ends with (Ground.enabled), applied to a saved map.
#include <cstddef>
#include <filesystem>

namespace crowdslam::system {

struct MapOptimiseOptions {
  int iterations = 20;  // Levenberg-Marquardt iterations, >= 1
  bool overwrite = false;  // replace an existing output file (which may be the input)
  // A monocular map of a camera at a constant height above the ground (a car's, --ground): also hold each
  // keyframe's ground at one height, with this relative sigma per keyframe (0 = off; io::GroundSettings).
  double ground_sigma = 0.0;

  // Throws InputError naming the bad option.
  void check() const;
};

// Reprojection statistics of a map: every observation of every map point (left image, pixels).
struct ReprojectionStats {
  std::size_t observations = 0;
  double rms_px = 0;             // root mean square reprojection error
  double median_px = 0;
  std::size_t above_chi2 = 0;    // observations with error^2 / sigma^2 of their level above 5.991
};

struct MapOptimiseReport {
  std::size_t keyframes = 0;
  std::size_t map_points = 0;
  ReprojectionStats before;
  ReprojectionStats after;
  int iterations = 0;            // solver iterations run
  double initial_cost = 0;       // robust cost (chi2 units)
  double final_cost = 0;
  double time_ms = 0;
  int keyframes_with_ground = 0;  // with ground_sigma: keyframes whose ground was held
  int ground_points = 0;
};

// Reads `input`, optimises, writes `output` atomically (a failure leaves no output and any old file as it
// was). Throws InputError for a bad or missing file, an existing output without `overwrite`, a map with
// fewer than two keyframes, or a bad option.
MapOptimiseReport optimise_saved_map(const std::filesystem::path& input, const std::filesystem::path& output,
                                     const MapOptimiseOptions& options);

}  // namespace crowdslam::system
