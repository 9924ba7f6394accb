#include "sen3bot/nav/cv_filter.hpp"

#include <cmath>

namespace sen3bot::nav {

bool CvFilter::finite() const noexcept {
  for (double v : x)
    if (!std::isfinite(v)) return false;
  for (double v : P)
    if (!std::isfinite(v)) return false;
  return true;
}

void CvFilter::reset(geometry::Point2D at, geometry::Point2D v, double position_var, double velocity_var) noexcept {
  x = {at.x_m, at.y_m, v.x_m, v.y_m};
  P = {};
  P[0] = P[5] = position_var;
  P[10] = P[15] = velocity_var;
}

void CvFilter::predict(double dt, double accel_sigma, ProcessNoise noise) noexcept {
  if (!(dt > 0.0)) return;
  x[0] += x[2] * dt;
  x[1] += x[3] * dt;
  // F P F' with F = [I dt I; 0 I]: rows 0, 1 gain dt times rows 2, 3, then the same for columns.
  std::array<double, 16> fp = P;
  for (int c = 0; c < 4; ++c) {
    fp[0 * 4 + c] += dt * P[2 * 4 + c];
    fp[1 * 4 + c] += dt * P[3 * 4 + c];
  }
  P = fp;
  for (int r = 0; r < 4; ++r) {
    P[r * 4 + 0] += dt * fp[r * 4 + 2];
    P[r * 4 + 1] += dt * fp[r * 4 + 3];
  }
  const double q = accel_sigma * accel_sigma;
  const double dt2 = dt * dt;
  const bool held = noise == ProcessNoise::piecewise_constant;
  const double pp = held ? q * dt2 * dt2 / 4.0 : q * dt2 * dt / 3.0;
  const double pv = held ? q * dt2 * dt / 2.0 : q * dt2 / 2.0;
  const double vv = held ? q * dt2 : q * dt;
  for (int a = 0; a < 2; ++a) {
    P[a * 4 + a] += pp;
    P[a * 4 + a + 2] += pv;
    P[(a + 2) * 4 + a] += pv;
    P[(a + 2) * 4 + a + 2] += vv;
  }
}

bool CvFilter::correct(geometry::Point2D z, double r00, double r01, double r11) noexcept {
  // S = H P H' + R with H = [I 0]: the position block plus the fix's covariance.
  const double s00 = P[0] + r00;
  const double s01 = P[1] + r01;
  const double s11 = P[5] + r11;
  const double det = s00 * s11 - s01 * s01;
  if (!(det > 0.0) || !std::isfinite(det) || !(s00 > 0.0)) return false;
  const double i00 = s11 / det;
  const double i01 = -s01 / det;
  const double i11 = s00 / det;
  double k[4][2];  // K = P H' S^-1
  for (int r = 0; r < 4; ++r) {
    k[r][0] = P[r * 4 + 0] * i00 + P[r * 4 + 1] * i01;
    k[r][1] = P[r * 4 + 0] * i01 + P[r * 4 + 1] * i11;
  }
  const double ex = z.x_m - x[0];
  const double ey = z.y_m - x[1];
  for (int r = 0; r < 4; ++r) x[r] += k[r][0] * ex + k[r][1] * ey;
  // Joseph form: (I - K H) P (I - K H)' + K R K'.
  double a[4][4];  // I - K H
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) a[r][c] = (r == c ? 1.0 : 0.0) - (c == 0 ? k[r][0] : c == 1 ? k[r][1] : 0.0);
  double ap[4][4];
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      double s = 0.0;
      for (int m = 0; m < 4; ++m) s += a[r][m] * P[m * 4 + c];
      ap[r][c] = s;
    }
  for (int r = 0; r < 4; ++r)
    for (int c = r; c < 4; ++c) {
      double s = 0.0;
      for (int m = 0; m < 4; ++m) s += ap[r][m] * a[c][m];
      s += k[r][0] * (r00 * k[c][0] + r01 * k[c][1]) + k[r][1] * (r01 * k[c][0] + r11 * k[c][1]);
      P[r * 4 + c] = P[c * 4 + r] = s;
    }
  return true;
}

}  // namespace sen3bot::nav
