#include "crowdslam/geometry/sim3.h"

#include <Eigen/LU>
#include <array>
#include <cmath>

namespace crowdslam::geometry {

namespace {

// I_m = integral_0^1 u^m e^(sigma u) du for m = 0..6.
std::array<double, 7> exp_moments(double sigma) {
  std::array<double, 7> moments{};
  if (std::abs(sigma) < 2.0) {
    // Series sum_k sigma^k / (k! (k + m + 1)); terms fall below 1e-18 by k = 30.
    for (int m = 0; m < 7; ++m) {
      double power = 1.0;  // sigma^k / k!
      double sum = 0.0;
      for (int k = 0; k < 30; ++k) {
        sum += power / (k + m + 1);
        power *= sigma / (k + 1);
      }
      moments[m] = sum;
    }
    return moments;
  }
  // Integration by parts: I_m = (e^sigma - m I_(m-1)) / sigma (stable for |sigma| >= 2 and m <= 6).
  const double e = std::exp(sigma);
  moments[0] = std::expm1(sigma) / sigma;
  for (int m = 1; m < 7; ++m) moments[m] = (e - m * moments[m - 1]) / sigma;
  return moments;
}

// W(phi, sigma) = a I + b K + c K^2 with K = skew(phi):
//   a = integral e^(sigma u), b = integral e^(sigma u) sin(theta u) / theta,
//   c = integral e^(sigma u) (1 - cos(theta u)) / theta^2.
Mat3 sim3_w(const Vec3& phi, double sigma) {
  const double theta = phi.norm();
  const std::array<double, 7> moment = exp_moments(sigma);
  const double a = moment[0];
  double b = 0.0;
  double c = 0.0;
  if (theta < 1e-3) {
    // Taylor series of sin and 1 - cos in theta, truncation error O(theta^6).
    const double t2 = theta * theta;
    b = moment[1] - t2 / 6.0 * moment[3] + t2 * t2 / 120.0 * moment[5];
    c = moment[2] / 2.0 - t2 / 24.0 * moment[4] + t2 * t2 / 720.0 * moment[6];
  } else {
    const double e = std::exp(sigma);
    const double st = std::sin(theta);
    const double ct = std::cos(theta);
    const double d = sigma * sigma + theta * theta;
    b = (e * (sigma * st - theta * ct) + theta) / (theta * d);
    c = (a - (e * (sigma * ct + theta * st) - sigma) / d) / (theta * theta);
  }
  const Mat3 k = skew(phi);
  return a * Mat3::Identity() + b * k + c * k * k;
}

}  // namespace

Sim3 Sim3::exp(const Vec7& tangent) {
  const Vec3 rho = tangent.head<3>();
  const Vec3 phi = tangent.segment<3>(3);
  const double sigma = tangent(6);
  return Sim3(so3_exp(phi), sim3_w(phi, sigma) * rho, std::exp(sigma));
}

Vec7 Sim3::log() const {
  const Vec3 phi = so3_log(rotation_matrix());
  const double sigma = std::log(scale_);
  Vec7 tangent;
  tangent.head<3>() = sim3_w(phi, sigma).partialPivLu().solve(translation_);
  tangent.segment<3>(3) = phi;
  tangent(6) = sigma;
  return tangent;
}

}  // namespace crowdslam::geometry
