#pragma once
// Feature number update (FNU, Crowd-SLAM): the fraction of the image covered by people in this frame sets
// the ORB feature budget of the next frame, so tracking keeps enough features on the static background.
#include <vector>

#include "crowdslam/people/detector.h"

namespace crowdslam::people {

enum class AreaMode { kSum, kUnion };  // paper: sum of box areas; extension: area of their union

struct FeatureBudgetOptions {
  int base_features = 1000;  // ORBextractor.nFeatures
  int image_width = 640;
  int image_height = 480;
  bool enabled = true;
  AreaMode area = AreaMode::kSum;
  // factor = factors[0] when a == 0 (no people); else factors[i] for the first i with a < thresholds[i]
  // (i >= 1); else factors.back(). Paper: thresholds {0, 0.3, 0.6, 0.9, 0.95}, factors
  // {1, 1.3, 1.5, 1.7, 1.9, 2.2}.
  std::vector<double> thresholds{0.0, 0.3, 0.6, 0.9, 0.95};
  std::vector<double> factors{1.0, 1.3, 1.5, 1.7, 1.9, 2.2};
  void check() const;
};

// Fraction of the image covered by the boxes (clipped to the image): sum of areas (may exceed 1 when boxes
// overlap) or the exact area of their union.
double covered_fraction(const std::vector<PersonBox>& boxes, int width, int height, AreaMode mode);

double budget_factor(double covered, const FeatureBudgetOptions& options);

// N scaled by image area / (640 x 480), times the factor for `covered`.
int feature_budget(double covered, const FeatureBudgetOptions& options);

}  // namespace crowdslam::people
