#include "skyloc/dsp/lens.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <random>

#include "support/angles.h"

namespace skyloc::dsp {
namespace {

LensParams Fisheye(LensModel model, int w, int h, double fov_deg) {
  LensParams p;
  p.model = model;
  p.width = w;
  p.height = h;
  p.fov_deg = fov_deg;
  return p;
}

// A synthetic OCamCalib calibration: an equidistant-like lens with mild distortion,
// ss chosen by hand, invpol fitted to it by least squares as OCamCalib's toolbox does.
LensParams SyntheticOCam(int invpol_terms) {
  LensParams p;
  p.model = LensModel::kOCamCalib;
  p.width = 640;
  p.height = 480;
  p.fov_deg = 180.0;
  p.radius_px = 235.0;
  OCamCalibModel& o = p.ocam;
  o.ss_count = 5;
  o.ss = {-150.0, 0.0, 1.2e-3, 1.0e-6, 2.0e-9};
  o.row_centre = 241.3;
  o.column_centre = 318.7;
  o.c = 1.001;
  o.d = 0.0004;
  o.e = -0.0003;
  o.width = 640;
  o.height = 480;
  if (invpol_terms > 0) {
    // Fit rho(t), t = atan(z / rho) in OCamCalib's frame (z = ss(rho) < 0).
    const int n = 400;
    Eigen::MatrixXd a(n, invpol_terms);
    Eigen::VectorXd b(n);
    for (int i = 0; i < n; ++i) {
      const double rho = 250.0 * (i + 0.5) / n;
      double z = 0;
      for (int j = o.ss_count - 1; j >= 0; --j)
        z = z * rho + o.ss[static_cast<std::size_t>(j)];
      const double t = std::atan(z / rho);
      for (int j = 0; j < invpol_terms; ++j)
        a(i, j) = std::pow(t, j);
      b(i) = rho;
    }
    const Eigen::VectorXd x = a.colPivHouseholderQr().solve(b);
    o.invpol_count = invpol_terms;
    for (int j = 0; j < invpol_terms; ++j)
      o.invpol[static_cast<std::size_t>(j)] = x(j);
  }
  return p;
}

// Round trip both ways at random points: pixel -> ray -> pixel, ray -> pixel -> ray.
void ExpectRoundTrips(const LensParams& params, double pixel_tolerance) {
  Lens lens;
  ASSERT_EQ(lens.Init(params), LensError::kOk) << LensModelName(params.model);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> ux(-0.5, params.width - 0.5);
  std::uniform_real_distribution<double> uy(-0.5, params.height - 0.5);
  int visible = 0;
  for (int i = 0; i < 4000; ++i) {
    const double x = ux(rng), y = uy(rng);
    Eigen::Vector3d ray;
    if (!lens.PixelToRay(x, y, &ray))
      continue;
    ++visible;
    EXPECT_NEAR(ray.norm(), 1.0, 1e-12);
    double bx = 0, by = 0;
    ASSERT_TRUE(lens.RayToPixel(ray, &bx, &by)) << x << "," << y;
    EXPECT_NEAR(bx, x, pixel_tolerance) << LensModelName(params.model) << " at " << x << "," << y;
    EXPECT_NEAR(by, y, pixel_tolerance) << LensModelName(params.model) << " at " << x << "," << y;
  }
  EXPECT_GT(visible, 1000);
  std::normal_distribution<double> g;
  int projected = 0;
  for (int i = 0; i < 4000; ++i) {
    // One draw per statement: a call's arguments are evaluated in an unspecified order
    // (right to left by GCC on x86-64, left to right on ARM).
    const double gz = g(rng);
    const double gy = g(rng);
    const double gx = g(rng);
    const Eigen::Vector3d ray = Eigen::Vector3d(gx, gy, gz).normalized();
    double x = 0, y = 0;
    if (!lens.RayToPixel(ray, &x, &y))
      continue;
    ++projected;
    Eigen::Vector3d back;
    ASSERT_TRUE(lens.PixelToRay(x, y, &back));
    EXPECT_LT((back - ray).norm(), 1e-9) << LensModelName(params.model);
  }
  EXPECT_GT(projected, 500);
}

TEST(Lens, EquidistantRoundTripsAndMapsRadiusToHalfFov) {
  LensParams p = Fisheye(LensModel::kEquidistant, 480, 480, 185.0);
  ExpectRoundTrips(p, 1e-9);
  Lens lens;
  ASSERT_EQ(lens.Init(p), LensError::kOk);
  Eigen::Vector3d ray;
  ASSERT_TRUE(lens.PixelToRay(239.5, 239.5, &ray));
  EXPECT_NEAR(ray(2), 1.0, 1e-15);
  // r = f * theta: half the radius is half of 92.5 degrees, along +x.
  ASSERT_TRUE(lens.PixelToRay(239.5 + 120.0, 239.5, &ray));
  EXPECT_NEAR(std::acos(ray(2)), 92.5 / 2 * kPi / 180, 1e-12);
  EXPECT_NEAR(ray(1), 0.0, 1e-15);
  EXPECT_GT(ray(0), 0.0);
  // Just outside the image circle is not visible.
  EXPECT_FALSE(lens.PixelToRay(239.5 + 240.5, 239.5, &ray));
  // Straight down is beyond 92.5 degrees.
  double x, y;
  EXPECT_FALSE(lens.RayToPixel({0, 0, -1}, &x, &y));
}

TEST(Lens, EquisolidMatchesItsFormula) {
  LensParams p = Fisheye(LensModel::kEquisolid, 640, 480, 180.0);
  ExpectRoundTrips(p, 1e-9);
  Lens lens;
  ASSERT_EQ(lens.Init(p), LensError::kOk);
  // f = R / (2 sin(45 deg)); a ray 60 degrees off axis lands at 2 f sin(30 deg) = f.
  const double f = 240.0 / (2 * std::sin(kPi / 4));
  double x, y;
  ASSERT_TRUE(lens.RayToPixel({std::sin(kPi / 3), 0, std::cos(kPi / 3)}, &x, &y));
  EXPECT_NEAR(x, 319.5 + f, 1e-9);
  EXPECT_NEAR(y, 239.5, 1e-12);
}

TEST(Lens, KannalaBrandtMatchesOpenCvFisheyeAtHandComputedPoints) {
  LensParams p = Fisheye(LensModel::kKannalaBrandt, 640, 480, 200.0);
  p.fx = 300.0;
  p.fy = 310.0;
  p.centre_x = 320.0;
  p.centre_y = 240.0;
  p.radius_px = 1000.0;  // the image border limits it, not a circle
  p.k = {0.1, -0.05, 0.01, -0.002};
  Lens lens;
  ASSERT_EQ(lens.Init(p), LensError::kOk);
  // Computed with OpenCV's documented cv::fisheye::projectPoints formula (a = X/Z,
  // r = |(a, b)|, theta = atan(r), theta_d polynomial, u = fx theta_d / r a + cx) in Python.
  struct Case {
    double X, Y, Z, u, v;
  } cases[] = {
      {0.3, -0.2, 1.0, 407.3524206517505, 179.82388799546075},
      {-1.5, 0.7, 1.0, 24.197274878305052, 382.64264744757287},
      {0.0, 0.05, 2.0, 320.0, 247.74886994311663},
  };
  for (const Case& c : cases) {
    double u, v;
    ASSERT_TRUE(lens.CameraRayToPixel({c.X, c.Y, c.Z}, &u, &v));
    EXPECT_NEAR(u, c.u, 1e-9);
    EXPECT_NEAR(v, c.v, 1e-9);
  }
  ExpectRoundTrips(p, 1e-8);
}

TEST(Lens, KannalaBrandtFoldingBackIsRejected) {
  LensParams p = Fisheye(LensModel::kKannalaBrandt, 640, 480, 180.0);
  p.fx = p.fy = 200.0;
  p.k = {-1.0, 0.0, 0.0, 0.0};  // theta (1 - theta^2) peaks at 33 degrees
  Lens lens;
  EXPECT_EQ(lens.Init(p), LensError::kNotMonotonic);
}

// OCamCalib's own cam2world (ocam_functions.cpp), in its frame: x = row, y = column.
Eigen::Vector3d OCamCam2World(const OCamCalibModel& o, double row, double col) {
  const double invdet = 1.0 / (o.c - o.d * o.e);
  const double xp = invdet * ((row - o.row_centre) - o.d * (col - o.column_centre));
  const double yp = invdet * (-o.e * (row - o.row_centre) + o.c * (col - o.column_centre));
  const double r = std::sqrt(xp * xp + yp * yp);
  double zp = o.ss[0], ri = 1;
  for (int i = 1; i < o.ss_count; ++i) {
    ri *= r;
    zp += ri * o.ss[static_cast<std::size_t>(i)];
  }
  return Eigen::Vector3d(xp, yp, zp).normalized();
}

// And its world2cam (invpol only).
void OCamWorld2Cam(const OCamCalibModel& o, const Eigen::Vector3d& p, double* row, double* col) {
  const double norm = std::sqrt(p(0) * p(0) + p(1) * p(1));
  const double theta = std::atan(p(2) / norm);
  double rho = o.invpol[0], ti = 1;
  for (int i = 1; i < o.invpol_count; ++i) {
    ti *= theta;
    rho += ti * o.invpol[static_cast<std::size_t>(i)];
  }
  const double x = p(0) / norm * rho, y = p(1) / norm * rho;
  *row = x * o.c + y * o.d + o.row_centre;
  *col = x * o.e + y + o.column_centre;
}

TEST(Lens, OCamCalibAgreesWithTheToolboxFunctionsAndRoundTrips) {
  const LensParams p = SyntheticOCam(12);
  Lens lens;
  ASSERT_EQ(lens.Init(p), LensError::kOk);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> angle(0, 2 * kPi), radius(0, 230);
  for (int i = 0; i < 300; ++i) {
    const double a = angle(rng), r = radius(rng);
    const double col = p.ocam.column_centre + r * std::cos(a);
    const double row = p.ocam.row_centre + r * std::sin(a);
    Eigen::Vector3d ray;
    ASSERT_TRUE(lens.PixelToCameraRay(col, row, &ray));
    const Eigen::Vector3d ref = OCamCam2World(p.ocam, row, col);
    // Ours is (column, row, optical axis) = (ref y, ref x, -ref z).
    EXPECT_NEAR(ray(0), ref(1), 1e-12);
    EXPECT_NEAR(ray(1), ref(0), 1e-12);
    EXPECT_NEAR(ray(2), -ref(2), 1e-12);
    // world2cam through the fitted invpol agrees to the fit's accuracy.
    double ref_row, ref_col, x, y;
    OCamWorld2Cam(p.ocam, ref, &ref_row, &ref_col);
    ASSERT_TRUE(lens.CameraRayToPixel(ray, &x, &y));
    EXPECT_NEAR(x, ref_col, 0.05);
    EXPECT_NEAR(y, ref_row, 0.05);
  }
  ExpectRoundTrips(p, 1e-8);
  ExpectRoundTrips(SyntheticOCam(0), 1e-8);  // without invpol: solved from ss alone
}

TEST(Lens, OCamCalibRejectsBadModels) {
  LensParams p = SyntheticOCam(0);
  Lens lens;
  p.ocam.ss[0] = 10.0;
  EXPECT_EQ(lens.Init(p), LensError::kBadOCamCalib);
  p = SyntheticOCam(0);
  p.width = 800;
  EXPECT_EQ(lens.Init(p), LensError::kBadImageSize);
  p = SyntheticOCam(0);
  p.ocam.ss[2] = -5e-3;  // z turns positive: the angle folds back
  EXPECT_EQ(lens.Init(p), LensError::kNotMonotonic);
}

TEST(Lens, EquirectangularCoversTheSphereWithRowZeroAtTheZenith) {
  LensParams p;
  p.model = LensModel::kEquirectangular;
  p.width = 720;
  p.height = 360;
  ExpectRoundTrips(p, 1e-9);
  Lens lens;
  ASSERT_EQ(lens.Init(p), LensError::kOk);
  Eigen::Vector3d ray;
  ASSERT_TRUE(lens.PixelToRay(100, -0.5, &ray));
  EXPECT_NEAR(ray(2), 1.0, 1e-12);
  ASSERT_TRUE(lens.PixelToRay(100, 359.5, &ray));
  EXPECT_NEAR(ray(2), -1.0, 1e-12);
  // Column for azimuth 90 degrees (+y) on the horizon.
  double x, y;
  ASSERT_TRUE(lens.RayToPixel({0, 1, 0}, &x, &y));
  EXPECT_NEAR(x, 720.0 / 4 - 0.5, 1e-9);
  EXPECT_NEAR(y, 179.5, 1e-9);
  ASSERT_TRUE(lens.RayToPixel({0, 0, -1}, &x, &y));  // everything is visible
}

// The Nao's camera of the 1D SURF paper: 640 x 480, 47.8 degrees across the width. A point
// (X, Y, Z) in the camera frame lands at (cx + f X / Z, cy + f Y / Z) with
// f = 320 / tan(23.9 degrees): the textbook perspective projection, written out here.
TEST(Lens, PinholeProjectsAsTheTextbookPerspectiveFormula) {
  LensParams p;
  p.model = LensModel::kPinhole;
  p.width = 640;
  p.height = 480;
  p.fov_deg = 47.8;
  Lens lens;
  ASSERT_EQ(lens.Init(p), LensError::kOk);
  const double f = 320.0 / std::tan(23.9 * kPi / 180.0);
  const double points[][3] = {{0, 0, 1}, {1, 0, 4}, {-2, 1.5, 9}, {0.3, -0.2, 0.7}};
  for (const auto& q : points) {
    double x, y;
    ASSERT_TRUE(lens.CameraRayToPixel({q[0], q[1], q[2]}, &x, &y));
    EXPECT_NEAR(x, 319.5 + f * q[0] / q[2], 1e-9);
    EXPECT_NEAR(y, 239.5 + f * q[1] / q[2], 1e-9);
  }
  // The image's left and right edges are 23.9 degrees off the axis.
  Eigen::Vector3d ray;
  ASSERT_TRUE(lens.PixelToCameraRay(639.5, 239.5, &ray));
  EXPECT_NEAR(std::atan2(ray(0), ray(2)) * 180.0 / kPi, 23.9, 1e-9);
  ASSERT_TRUE(lens.PixelToCameraRay(-0.5, -0.5, &ray));  // every corner is in view
  ASSERT_TRUE(lens.PixelToCameraRay(639.5, 479.5, &ray));
  double x, y;
  EXPECT_FALSE(lens.CameraRayToPixel({0, 0, -1}, &x, &y));    // behind the camera
  EXPECT_FALSE(lens.CameraRayToPixel({1, 0, 1}, &x, &y));     // 45 degrees: beyond the edge
  EXPECT_FALSE(lens.CameraRayToPixel({1, 0, 1e-9}, &x, &y));  // nearly sideways
  // Pixel -> ray -> pixel over the image (ExpectRoundTrips' random rays would mostly miss
  // a 48-degree view).
  for (double px = 0.0; px <= 639.0; px += 31.9) {
    for (double py = 0.0; py <= 479.0; py += 23.9) {
      ASSERT_TRUE(lens.PixelToRay(px, py, &ray)) << px << "," << py;
      ASSERT_TRUE(lens.RayToPixel(ray, &x, &y)) << px << "," << py;
      EXPECT_NEAR(x, px, 1e-9);
      EXPECT_NEAR(y, py, 1e-9);
    }
  }
  p.fov_deg = 180.0;
  EXPECT_EQ(lens.Init(p), LensError::kBadFieldOfView);
  LensModel m;
  ASSERT_TRUE(ParseLensModel("pinhole", &m));
  EXPECT_EQ(m, LensModel::kPinhole);
}

TEST(Lens, MountRotationAppliesRollPitchYawInOrder) {
  LensParams p = Fisheye(LensModel::kEquidistant, 480, 480, 185.0);
  p.pitch_deg = 90.0;
  Lens lens;
  ASSERT_EQ(lens.Init(p), LensError::kOk);
  Eigen::Vector3d ray;
  ASSERT_TRUE(lens.PixelToRay(239.5, 239.5, &ray));  // the optical axis
  EXPECT_NEAR(ray(0), 1.0, 1e-12);                   // Ry(90) (0,0,1) = (1,0,0)
  ExpectRoundTrips(p, 1e-9);

  p.pitch_deg = 0.0;
  p.roll_deg = 30.0;
  p.yaw_deg = 90.0;
  ASSERT_EQ(lens.Init(p), LensError::kOk);
  ASSERT_TRUE(lens.PixelToRay(239.5, 239.5, &ray));
  // Rx(30) (0,0,1) = (0, -sin 30, cos 30); then Rz(90) maps (x, y) -> (-y, x).
  EXPECT_NEAR(ray(0), 0.5, 1e-12);
  EXPECT_NEAR(ray(1), 0.0, 1e-12);
  EXPECT_NEAR(ray(2), std::cos(kPi / 6), 1e-12);
}

TEST(Lens, InvalidParametersAreReported) {
  Lens lens;
  LensParams p = Fisheye(LensModel::kEquidistant, 0, 480, 185.0);
  EXPECT_EQ(lens.Init(p), LensError::kBadImageSize);
  p = Fisheye(LensModel::kEquidistant, 480, 480, 0.0);
  EXPECT_EQ(lens.Init(p), LensError::kBadFieldOfView);
  p = Fisheye(LensModel::kEquidistant, 480, 480, 185.0);
  p.radius_px = -3;
  EXPECT_EQ(lens.Init(p), LensError::kBadRadius);
  p.radius_px = LensParams::kUnset;
  p.yaw_deg = std::numeric_limits<double>::infinity();
  EXPECT_EQ(lens.Init(p), LensError::kBadMountAngle);
  p = Fisheye(LensModel::kKannalaBrandt, 480, 480, 185.0);
  EXPECT_EQ(lens.Init(p), LensError::kBadFocalLength);
  EXPECT_NE(std::string(LensErrorMessage(LensError::kNotMonotonic)).find("field of view"),
            std::string::npos);
  LensModel m;
  ASSERT_TRUE(ParseLensModel("kannala_brandt", &m));
  EXPECT_EQ(m, LensModel::kKannalaBrandt);
  EXPECT_FALSE(ParseLensModel("fisheye", &m));
}

}  // namespace
}  // namespace skyloc::dsp
