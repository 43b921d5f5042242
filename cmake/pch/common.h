// Precompiled header of the crowdslam libraries (cmake/BuildSpeed.cmake): the third-party headers most
// translation units include, parsed once per target instead of once per file. Only system and
// third-party headers belong here; sources still include what they use.
#pragma once
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
