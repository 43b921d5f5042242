#pragma once
// Angle constants shared by the modules (the C++17 standard library has no std::numbers).

namespace crowdslam::geometry {

inline constexpr double kPi = 3.14159265358979323846;

}  // namespace crowdslam::geometry
