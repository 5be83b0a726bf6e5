#include "skyloc/dsp/lens.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include "skyloc/dsp/angles.h"

namespace skyloc::dsp {
namespace {

// Solves f(t) = target for t in [lo, hi] where f increases monotonically: Newton steps
// from `guess`, falling back to bisection whenever a step leaves the bracket. `f` returns
// the value and writes the derivative.
template <typename F>
double SolveIncreasing(const F& f, double target, double lo, double hi, double guess) {
  double t = (guess >= lo && guess <= hi && std::isfinite(guess)) ? guess : 0.5 * (lo + hi);
  for (int i = 0; i < 100; ++i) {
    double derivative = 0.0;
    const double value = f(t, &derivative) - target;
    if (value > 0.0)
      hi = t;
    else
      lo = t;
    if (std::fabs(value) <= 1e-13 * (1.0 + std::fabs(target)) || hi - lo <= 1e-15 * (1.0 + hi))
      return t;
    double next = derivative > 0.0 ? t - value / derivative : 0.5 * (lo + hi);
    if (!(next > lo && next < hi))
      next = 0.5 * (lo + hi);
    t = next;
  }
  return t;
}

Eigen::Vector3d FromPolar(double theta, double dx, double dy, double r) {
  if (r <= 0.0)
    return {0.0, 0.0, 1.0};
  const double s = std::sin(theta) / r;
  return {s * dx, s * dy, std::cos(theta)};
}

}  // namespace

const char* LensModelName(LensModel model) {
  switch (model) {
    case LensModel::kEquidistant:
      return "equidistant";
    case LensModel::kEquisolid:
      return "equisolid";
    case LensModel::kKannalaBrandt:
      return "kannala_brandt";
    case LensModel::kOCamCalib:
      return "ocamcalib";
    case LensModel::kEquirectangular:
      return "equirectangular";
    case LensModel::kPinhole:
      return "pinhole";
  }
  return "unknown";
}

bool ParseLensModel(const char* name, LensModel* model) {
  for (LensModel m : {LensModel::kEquidistant, LensModel::kEquisolid, LensModel::kKannalaBrandt,
                      LensModel::kOCamCalib, LensModel::kEquirectangular, LensModel::kPinhole}) {
    if (std::strcmp(name, LensModelName(m)) == 0) {
      *model = m;
      return true;
    }
  }
  return false;
}

const char* LensErrorMessage(LensError error) {
  switch (error) {
    case LensError::kOk:
      return "ok";
    case LensError::kBadImageSize:
      return "the image size must be positive and, for OCamCalib, the size the calibration "
             "was made for";
    case LensError::kBadFieldOfView:
      return "the field of view must be in (0, 360] degrees (a pinhole's in (0, 180))";
    case LensError::kBadRadius:
      return "the image-circle radius must be a positive number of pixels";
    case LensError::kBadCentre:
      return "the optical centre must be finite pixel coordinates";
    case LensError::kBadFocalLength:
      return "Kannala-Brandt fx and fy must be positive pixels";
    case LensError::kNotMonotonic:
      return "the lens distortion folds back inside the field of view: reduce the field of "
             "view or recalibrate";
    case LensError::kBadOCamCalib:
      return "the OCamCalib model needs ss with ss[0] < 0 and an invertible affine matrix "
             "(c - d*e != 0)";
    case LensError::kBadMountAngle:
      return "mount roll/pitch/yaw must be finite degrees";
  }
  return "unknown lens error";
}

LensError Lens::Init(const LensParams& params) {
  params_ = params;
  if (params.width <= 0 || params.height <= 0)
    return LensError::kBadImageSize;
  if (!std::isfinite(params.roll_deg) || !std::isfinite(params.pitch_deg) ||
      !std::isfinite(params.yaw_deg))
    return LensError::kBadMountAngle;
  camera_to_body_ = (Eigen::AngleAxisd(params.yaw_deg * kDegToRad, Eigen::Vector3d::UnitZ()) *
                     Eigen::AngleAxisd(params.pitch_deg * kDegToRad, Eigen::Vector3d::UnitY()) *
                     Eigen::AngleAxisd(params.roll_deg * kDegToRad, Eigen::Vector3d::UnitX()))
                        .toRotationMatrix();
  if (params.model == LensModel::kEquirectangular) {
    centre_x_ = (params.width - 1) / 2.0;
    centre_y_ = (params.height - 1) / 2.0;
    radius_px_ = 0.0;
    max_theta_ = kPi;
    return LensError::kOk;
  }

  if (!(params.fov_deg > 0.0 && params.fov_deg <= 360.0))
    return LensError::kBadFieldOfView;
  max_theta_ = std::min(params.fov_deg * kDegToRad / 2.0, kPi);
  if (params.model == LensModel::kOCamCalib) {
    centre_x_ = params.ocam.column_centre;
    centre_y_ = params.ocam.row_centre;
  } else {
    centre_x_ = std::isnan(params.centre_x) ? (params.width - 1) / 2.0 : params.centre_x;
    centre_y_ = std::isnan(params.centre_y) ? (params.height - 1) / 2.0 : params.centre_y;
  }
  if (!std::isfinite(centre_x_) || !std::isfinite(centre_y_))
    return LensError::kBadCentre;
  if (params.model == LensModel::kPinhole) {
    if (!(params.fov_deg < 180.0))
      return LensError::kBadFieldOfView;
    focal_ = params.width / 2.0 / std::tan(params.fov_deg * kDegToRad / 2.0);
    // No image circle: the "circle" reaches the farthest image corner, so only the image's
    // own edges limit the view, and max_theta is the angle of that corner.
    radius_px_ = 0.0;
    for (double cx : {-0.5, params.width - 0.5})
      for (double cy : {-0.5, params.height - 0.5})
        radius_px_ = std::max(radius_px_, std::hypot(cx - centre_x_, cy - centre_y_));
    max_theta_ = std::atan(radius_px_ / focal_);
    return LensError::kOk;
  }
  radius_px_ =
      std::isnan(params.radius_px) ? std::min(params.width, params.height) / 2.0 : params.radius_px;
  if (!(radius_px_ > 0.0) || !std::isfinite(radius_px_))
    return LensError::kBadRadius;

  switch (params.model) {
    case LensModel::kEquidistant:
      focal_ = radius_px_ / max_theta_;
      return LensError::kOk;
    case LensModel::kEquisolid:
      focal_ = radius_px_ / (2.0 * std::sin(max_theta_ / 2.0));
      return LensError::kOk;
    case LensModel::kKannalaBrandt: {
      if (!(params.fx > 0.0) || !(params.fy > 0.0) || !std::isfinite(params.fx) ||
          !std::isfinite(params.fy))
        return LensError::kBadFocalLength;
      for (double k : params.k)
        if (!std::isfinite(k))
          return LensError::kNotMonotonic;
      // theta_d must increase over the field of view, or pixels would have two rays.
      double previous = 0.0;
      for (int i = 1; i <= 2000; ++i) {
        const double d = KannalaBrandtDistort(max_theta_ * i / 2000.0);
        if (!(d > previous))
          return LensError::kNotMonotonic;
        previous = d;
      }
      return LensError::kOk;
    }
    case LensModel::kOCamCalib: {
      const OCamCalibModel& o = params.ocam;
      if (o.ss_count < 1 || o.ss_count > OCamCalibModel::kMaxTerms || !(o.ss[0] < 0.0) ||
          o.invpol_count < 0 || o.invpol_count > OCamCalibModel::kMaxTerms)
        return LensError::kBadOCamCalib;
      const double det = o.c - o.d * o.e;
      if (!(std::fabs(det) > 1e-9))
        return LensError::kBadOCamCalib;
      ocam_inverse_det_ = 1.0 / det;
      if ((o.width > 0 && o.width != params.width) || (o.height > 0 && o.height != params.height))
        return LensError::kBadImageSize;
      // The angle from the axis must increase with the pixel radius out to the circle.
      double previous = 0.0;
      const double limit = radius_px_ * 1.5 + 2.0;
      for (int i = 1; i <= 2000; ++i) {
        const double rho = limit * i / 2000.0;
        const double theta = std::atan2(rho, -OCamZ(rho));
        if (!(theta > previous))
          return LensError::kNotMonotonic;
        if (theta > max_theta_)
          break;
        previous = theta;
      }
      return LensError::kOk;
    }
    case LensModel::kEquirectangular:
    case LensModel::kPinhole:
      break;
  }
  return LensError::kOk;
}

double Lens::KannalaBrandtDistort(double theta) const {
  const double t2 = theta * theta;
  const auto& k = params_.k;
  return theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
}

double Lens::OCamZ(double rho) const {
  const OCamCalibModel& o = params_.ocam;
  double z = 0.0;
  for (int i = o.ss_count - 1; i >= 0; --i)
    z = z * rho + o.ss[static_cast<std::size_t>(i)];
  return z;
}

double Lens::OCamRadiusForTheta(double theta) const {
  const OCamCalibModel& o = params_.ocam;
  // invpol is a fit in OCamCalib's angle t = atan(z / norm), which for our optical axis
  // (OCamCalib's -z) is theta - pi/2.
  double guess = -1.0;
  if (o.invpol_count > 0) {
    const double t = theta - kPi / 2.0;
    guess = 0.0;
    for (int i = o.invpol_count - 1; i >= 0; --i)
      guess = guess * t + o.invpol[static_cast<std::size_t>(i)];
  }
  // Newton on g(rho) = atan2(rho, -ss(rho)) = theta, bracketed by the monotonic range.
  const auto angle = [this](double rho, double* derivative) {
    const OCamCalibModel& m = params_.ocam;
    double z = 0.0, dz = 0.0;
    for (int i = m.ss_count - 1; i >= 0; --i) {
      dz = dz * rho + z;
      z = z * rho + m.ss[static_cast<std::size_t>(i)];
    }
    // d/drho atan2(rho, -z) = (-z + rho * dz) / (rho^2 + z^2)
    *derivative = (-z + rho * dz) / (rho * rho + z * z);
    return std::atan2(rho, -z);
  };
  return SolveIncreasing(angle, theta, 0.0, radius_px_ * 1.5 + 2.0, guess);
}

bool Lens::InImage(double x, double y) const {
  return x >= -0.5 && y >= -0.5 && x <= params_.width - 0.5 && y <= params_.height - 0.5;
}

bool Lens::PixelToCameraRay(double x, double y, Eigen::Vector3d* ray) const {
  if (!std::isfinite(x) || !std::isfinite(y) || !InImage(x, y))
    return false;
  if (params_.model == LensModel::kEquirectangular) {
    const double theta = (y + 0.5) * kPi / params_.height;
    const double phi = (x + 0.5) * 2.0 * kPi / params_.width;
    *ray = {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
    return true;
  }
  const double dx = x - centre_x_;
  const double dy = y - centre_y_;
  const double r = std::hypot(dx, dy);
  if (r > radius_px_)
    return false;
  double theta = 0.0;
  switch (params_.model) {
    case LensModel::kEquidistant:
      theta = r / focal_;
      break;
    case LensModel::kEquisolid: {
      const double s = r / (2.0 * focal_);
      if (s > 1.0)
        return false;
      theta = 2.0 * std::asin(s);
      break;
    }
    case LensModel::kKannalaBrandt: {
      const double mx = dx / params_.fx;
      const double my = dy / params_.fy;
      const double theta_d = std::hypot(mx, my);
      if (theta_d > KannalaBrandtDistort(max_theta_))
        return false;
      const auto distort = [this](double t, double* derivative) {
        const double t2 = t * t;
        const auto& k = params_.k;
        *derivative =
            1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
        return KannalaBrandtDistort(t);
      };
      theta = SolveIncreasing(distort, theta_d, 0.0, max_theta_, theta_d);
      *ray = FromPolar(theta, mx, my, theta_d);
      return theta <= max_theta_;
    }
    case LensModel::kOCamCalib: {
      const OCamCalibModel& o = params_.ocam;
      const double row = y - o.row_centre;
      const double col = x - o.column_centre;
      // OCamCalib's frame: x along rows, y along columns, z = -optical axis.
      const double ox = ocam_inverse_det_ * (row - o.d * col);
      const double oy = ocam_inverse_det_ * (-o.e * row + o.c * col);
      const double oz = OCamZ(std::hypot(ox, oy));
      Eigen::Vector3d v(oy, ox, -oz);
      *ray = v.normalized();
      return std::acos(std::clamp((*ray)(2), -1.0, 1.0)) <= max_theta_;
    }
    case LensModel::kPinhole:
      theta = std::atan(r / focal_);
      break;
    case LensModel::kEquirectangular:
      return false;
  }
  if (theta > max_theta_)
    return false;
  *ray = FromPolar(theta, dx, dy, r);
  return true;
}

bool Lens::CameraRayToPixel(const Eigen::Vector3d& ray, double* x, double* y) const {
  const double n = ray.norm();
  if (!(n > 0.0) || !std::isfinite(n))
    return false;
  const Eigen::Vector3d d = ray / n;
  const double rho = std::hypot(d(0), d(1));
  const double theta = std::atan2(rho, d(2));
  if (params_.model == LensModel::kEquirectangular) {
    double phi = std::atan2(d(1), d(0));
    if (phi < 0.0)
      phi += 2.0 * kPi;
    double px = phi * params_.width / (2.0 * kPi) - 0.5;
    if (px >= params_.width - 0.5)
      px -= params_.width;
    *x = px;
    *y = theta * params_.height / kPi - 0.5;
    return true;
  }
  if (theta > max_theta_ * (1.0 + 1e-12))
    return false;
  const double ux = rho > 0.0 ? d(0) / rho : 0.0;
  const double uy = rho > 0.0 ? d(1) / rho : 0.0;
  double px = 0.0, py = 0.0;
  switch (params_.model) {
    case LensModel::kEquidistant:
      px = centre_x_ + focal_ * theta * ux;
      py = centre_y_ + focal_ * theta * uy;
      break;
    case LensModel::kEquisolid: {
      const double r = 2.0 * focal_ * std::sin(theta / 2.0);
      px = centre_x_ + r * ux;
      py = centre_y_ + r * uy;
      break;
    }
    case LensModel::kKannalaBrandt: {
      const double theta_d = KannalaBrandtDistort(theta);
      px = centre_x_ + params_.fx * theta_d * ux;
      py = centre_y_ + params_.fy * theta_d * uy;
      break;
    }
    case LensModel::kOCamCalib: {
      const OCamCalibModel& o = params_.ocam;
      const double r = OCamRadiusForTheta(theta);
      const double ox = uy * r;  // OCamCalib x runs along rows = our y
      const double oy = ux * r;
      py = ox * o.c + oy * o.d + o.row_centre;
      px = ox * o.e + oy + o.column_centre;
      break;
    }
    case LensModel::kPinhole:
      px = centre_x_ + focal_ * d(0) / d(2);
      py = centre_y_ + focal_ * d(1) / d(2);
      break;
    case LensModel::kEquirectangular:
      return false;
  }
  if (std::hypot(px - centre_x_, py - centre_y_) > radius_px_ * (1.0 + 1e-12) || !InImage(px, py))
    return false;
  *x = px;
  *y = py;
  return true;
}

bool Lens::PixelToRay(double x, double y, Eigen::Vector3d* ray) const {
  Eigen::Vector3d camera;
  if (!PixelToCameraRay(x, y, &camera))
    return false;
  *ray = camera_to_body_ * camera;
  return true;
}

bool Lens::RayToPixel(const Eigen::Vector3d& ray, double* x, double* y) const {
  return CameraRayToPixel(camera_to_body_.transpose() * ray, x, y);
}

}  // namespace skyloc::dsp
