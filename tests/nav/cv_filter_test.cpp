// The tracking kit's constant-velocity filter against the textbook matrix formulas written out
// with general matrix products, and on a noisy straight walk.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "sen3bot/nav/cv_filter.hpp"

namespace sen3bot::nav {
namespace {

using M4 = std::array<std::array<double, 4>, 4>;

M4 from(const std::array<double, 16>& p) {
  M4 m{};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m[r][c] = p[r * 4 + c];
  return m;
}

M4 mul(const M4& a, const M4& b) {
  M4 m{};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      for (int k = 0; k < 4; ++k) m[r][c] += a[r][k] * b[k][c];
  return m;
}

M4 transpose(const M4& a) {
  M4 m{};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m[r][c] = a[c][r];
  return m;
}

CvFilter spread_filter() {
  CvFilter f;
  f.x = {1.0, -2.0, 0.8, 0.3};
  // A full, positive definite covariance: every term of the formulas takes part.
  const M4 l{{{0.3, 0, 0, 0}, {0.05, 0.25, 0, 0}, {0.1, -0.02, 0.6, 0}, {-0.03, 0.07, 0.1, 0.5}}};
  const M4 p = mul(l, transpose(l));
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) f.P[r * 4 + c] = p[r][c];
  return f;
}

void expect_matrix_near(const std::array<double, 16>& got, const M4& want, double tol) {
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(got[r * 4 + c], want[r][c], tol) << "(" << r << ", " << c << ")";
}

TEST(CvFilter, PredictionIsFPFtPlusEitherNoiseModel) {
  const double dt = 0.35;
  const double sigma = 0.8;
  const M4 f{{{1, 0, dt, 0}, {0, 1, 0, dt}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
  for (ProcessNoise noise : {ProcessNoise::piecewise_constant, ProcessNoise::continuous}) {
    CvFilter kf = spread_filter();
    M4 want = mul(mul(f, from(kf.P)), transpose(f));
    const double q = sigma * sigma;
    const bool held = noise == ProcessNoise::piecewise_constant;
    const double pp = held ? q * std::pow(dt, 4) / 4 : q * std::pow(dt, 3) / 3;
    const double pv = held ? q * std::pow(dt, 3) / 2 : q * dt * dt / 2;
    const double vv = held ? q * dt * dt : q * dt;
    for (int a = 0; a < 2; ++a) {
      want[a][a] += pp;
      want[a][a + 2] += pv;
      want[a + 2][a] += pv;
      want[a + 2][a + 2] += vv;
    }
    kf.predict(dt, sigma, noise);
    expect_matrix_near(kf.P, want, 1e-12);
    EXPECT_DOUBLE_EQ(kf.x[0], 1.0 + 0.8 * dt);
    EXPECT_DOUBLE_EQ(kf.x[1], -2.0 + 0.3 * dt);
  }
}

TEST(CvFilter, ContinuousNoiseDoesNotDependOnHowTheTimeIsCut) {
  CvFilter once = spread_filter();
  CvFilter steps = once;
  once.predict(2.0, 0.5, ProcessNoise::continuous);
  for (int i = 0; i < 20; ++i) steps.predict(0.1, 0.5, ProcessNoise::continuous);
  expect_matrix_near(steps.P, from(once.P), 1e-9);
}

TEST(CvFilter, CorrectionIsTheKalmanUpdateAndKeepsPSymmetric) {
  CvFilter kf = spread_filter();
  const double r00 = 0.02, r01 = 0.006, r11 = 0.01;
  const geometry::Point2D z{1.3, -1.7};
  // K = P H' S^-1 written out with H = [I 0].
  const M4 p = from(kf.P);
  const double s00 = p[0][0] + r00, s01 = p[0][1] + r01, s11 = p[1][1] + r11;
  const double det = s00 * s11 - s01 * s01;
  double k[4][2];
  for (int r = 0; r < 4; ++r) {
    k[r][0] = (p[r][0] * s11 - p[r][1] * s01) / det;
    k[r][1] = (-p[r][0] * s01 + p[r][1] * s00) / det;
  }
  std::array<double, 4> x = kf.x;
  for (int r = 0; r < 4; ++r) x[r] += k[r][0] * (z.x_m - kf.x[0]) + k[r][1] * (z.y_m - kf.x[1]);
  M4 ikh{};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) ikh[r][c] = (r == c ? 1.0 : 0.0) - (c < 2 ? k[r][c] : 0.0);
  const M4 want = mul(ikh, p);  // (I - K H) P, equal to the Joseph form for this gain

  ASSERT_TRUE(kf.correct(z, r00, r01, r11));
  for (int r = 0; r < 4; ++r) EXPECT_NEAR(kf.x[r], x[r], 1e-12);
  expect_matrix_near(kf.P, want, 1e-12);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) EXPECT_EQ(kf.P[r * 4 + c], kf.P[c * 4 + r]);
  EXPECT_LT(kf.cov(0, 0), p[0][0]);
  EXPECT_LT(kf.cov(1, 1), p[1][1]);
}

TEST(CvFilter, ABrokenStateOrFixIsRefusedAndLeftAsItWas) {
  CvFilter kf = spread_filter();
  const CvFilter before = kf;
  EXPECT_FALSE(kf.correct({1.0, 1.0}, -10.0, 0.0, -10.0));  // S not positive definite
  CvFilter broken = spread_filter();
  broken.P[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(broken.finite());
  EXPECT_FALSE(broken.correct({1.0, 1.0}, 0.01, 0.0, 0.01));
  EXPECT_EQ(kf.x, before.x);
  EXPECT_EQ(kf.P, before.P);
  kf.predict(0.0, 1.0, ProcessNoise::continuous);
  kf.predict(std::numeric_limits<double>::quiet_NaN(), 1.0, ProcessNoise::continuous);
  EXPECT_EQ(kf.P, before.P);
  EXPECT_TRUE(kf.finite());
}

TEST(CvFilter, FollowsANoisyWalkAndItsSpreadCoversTheError) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.07);
  const geometry::Point2D v{1.1, -0.4};
  CvFilter kf;
  kf.reset({0.0, 0.0}, {}, 0.07 * 0.07, 1.5 * 1.5);
  int inside = 0;
  constexpr int kSteps = 200;
  for (int i = 1; i <= kSteps; ++i) {
    const double t = 0.075 * i;
    kf.predict(0.075, 0.5, ProcessNoise::piecewise_constant);
    ASSERT_TRUE(kf.correct({v.x_m * t + noise(rng), v.y_m * t + noise(rng)}, 0.07 * 0.07, 0.0, 0.07 * 0.07));
    const double ex = kf.x[0] - v.x_m * t;
    if (i > 20 && std::abs(ex) < 2.0 * std::sqrt(kf.cov(0, 0))) ++inside;
  }
  EXPECT_NEAR(kf.x[2], v.x_m, 0.1);
  EXPECT_NEAR(kf.x[3], v.y_m, 0.1);
  EXPECT_GE(inside, 160);  // about 95 % of 180 within two sigma: the spread is honest
}

}  // namespace
}  // namespace sen3bot::nav
