// Camera/lens models: pixel <-> unit direction, then the camera-to-body rotation.
//
// Pixel coordinates: x = column (right), y = row (down), pixel centres at integers (the
// OpenCV convention), so a W x H image spans [-0.5, W-0.5] x [-0.5, H-0.5].
// Camera frame: x along image columns, y along image rows, z = optical axis (the OpenCV
// camera frame). An upward camera's optical axis is "up"; with zero mount angles the body
// frame is the camera frame.
// Body frame: body = R * camera, R = Rz(yaw) * Ry(pitch) * Rx(roll) (angles in degrees,
// applied roll first). The sky is sampled in the body frame: elevation measured from +z.
//
// Models (the fisheye ones measure theta, the angle from the optical axis):
//   equidistant      r = f * theta                  f from fov and image-circle radius
//   equisolid        r = 2 f sin(theta / 2)         f from fov and image-circle radius
//   kannala_brandt   OpenCV cv::fisheye: theta_d = theta (1 + k1 t^2 + k2 t^4 + k3 t^6 + k4 t^8),
//                    u = fx * theta_d * X / rho + cx, v = fy * theta_d * Y / rho + cy
//                    (rho = sqrt(X^2 + Y^2)); valid beyond 90 degrees, unlike x/z
//   ocamcalib        Scaramuzza's OCamCalib calib_results.txt: ss (pixel radius -> z,
//                    cam2world), invpol (angle -> pixel radius, world2cam), centre xc (row)
//                    yc (column), affine c d e. Ray -> pixel starts from invpol and refines
//                    with Newton on ss, so the two directions agree exactly.
//   pinhole          r = f * tan(theta): an undistorted perspective camera; fov_deg is the
//                    full horizontal field of view across the image width (below 180), so
//                    f = (W / 2) / tan(fov / 2); no image circle (every pixel of the image
//                    is in view; radius_px is not used)
//   equirectangular  an unfolded full-sphere panorama: row 0 is the zenith side, theta =
//                    (y + 0.5) * pi / H; columns are azimuth phi = (x + 0.5) * 2 pi / W
//                    measured from +x towards +y.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>

namespace skyloc::dsp {

enum class LensModel : std::uint8_t {
  kEquidistant,
  kEquisolid,
  kKannalaBrandt,
  kOCamCalib,
  kEquirectangular,
  kPinhole,
};

// The camera-file spelling: "equidistant", "equisolid", "kannala_brandt", "ocamcalib",
// "equirectangular", "pinhole".
const char* LensModelName(LensModel model);
// Parses that spelling; false for anything else.
bool ParseLensModel(const char* name, LensModel* model);

// The contents of an OCamCalib calib_results.txt (parsed outside dsp/).
struct OCamCalibModel {
  static constexpr int kMaxTerms = 32;
  std::array<double, kMaxTerms> ss{};  // cam2world: z = sum ss[i] rho^i (ss[0] < 0)
  int ss_count = 0;
  std::array<double, kMaxTerms> invpol{};  // world2cam: rho = sum invpol[i] t^i
  int invpol_count = 0;                    // 0: ray -> pixel solves ss alone
  double row_centre = 0.0;                 // "xc": the row of the optical centre
  double column_centre = 0.0;              // "yc": its column
  double c = 1.0, d = 0.0, e = 0.0;        // affine: [row; col] = [c d; e 1] [x; y] + centre
  int height = 0, width = 0;               // calibrated image size (0: not given)
};

struct LensParams {
  static constexpr double kUnset = std::numeric_limits<double>::quiet_NaN();

  LensModel model = LensModel::kEquidistant;
  int width = 0;
  int height = 0;
  // Optical centre in pixels; unset = the image centre ((W-1)/2, (H-1)/2). OCamCalib uses
  // the centre of its calibration (row_centre/column_centre) instead.
  double centre_x = kUnset;
  double centre_y = kUnset;
  // Image-circle radius in pixels; pixels farther from the centre are not sky. Unset =
  // half the shorter image side. Not used by equirectangular.
  double radius_px = kUnset;
  // Full field of view (degrees) across the image circle: directions beyond fov/2 from
  // the optical axis are not visible. For equidistant/equisolid it also fixes f. For
  // pinhole: the horizontal field of view across the image width, which fixes f.
  double fov_deg = 185.0;
  // Kannala-Brandt focal lengths (pixels) and distortion k1..k4.
  double fx = 0.0;
  double fy = 0.0;
  std::array<double, 4> k{};
  OCamCalibModel ocam;
  // Camera-to-body mount rotation, degrees.
  double roll_deg = 0.0;
  double pitch_deg = 0.0;
  double yaw_deg = 0.0;
};

enum class LensError : std::uint8_t {
  kOk,
  kBadImageSize,    // width/height <= 0, or not the size an OCamCalib file was made for
  kBadFieldOfView,  // fov outside (0, 360], or a pinhole's outside (0, 180)
  kBadRadius,       // radius <= 0 or not finite
  kBadCentre,       // centre not finite
  kBadFocalLength,  // Kannala-Brandt fx/fy <= 0
  kNotMonotonic,    // the distortion folds back inside the field of view
  kBadOCamCalib,    // ss missing, ss[0] >= 0, or a singular affine matrix
  kBadMountAngle,   // a mount angle is not finite
};

// A sentence naming the problem and the fix, e.g. for kNotMonotonic.
const char* LensErrorMessage(LensError error);

class Lens {
 public:
  // Validates the parameters and precomputes the projection. Not for the frame path.
  LensError Init(const LensParams& params);

  const LensParams& params() const { return params_; }
  double centre_x() const { return centre_x_; }
  double centre_y() const { return centre_y_; }
  double radius_px() const { return radius_px_; }
  // Half the field of view, radians.
  double max_theta() const { return max_theta_; }
  const Eigen::Matrix3d& camera_to_body() const { return camera_to_body_; }

  // Pixel -> unit ray in the camera frame. False when the pixel is outside the image,
  // outside the image circle or beyond the field of view.
  bool PixelToCameraRay(double x, double y, Eigen::Vector3d* ray) const;
  // Camera-frame direction (need not be unit) -> pixel. False when it is not visible:
  // beyond the field of view, outside the image circle or outside the image.
  bool CameraRayToPixel(const Eigen::Vector3d& ray, double* x, double* y) const;

  // The same in the body frame (the mount rotation applied).
  bool PixelToRay(double x, double y, Eigen::Vector3d* ray) const;
  bool RayToPixel(const Eigen::Vector3d& ray, double* x, double* y) const;

 private:
  bool InImage(double x, double y) const;
  double KannalaBrandtDistort(double theta) const;
  double OCamZ(double rho) const;
  double OCamRadiusForTheta(double theta) const;

  LensParams params_;
  double centre_x_ = 0.0;
  double centre_y_ = 0.0;
  double radius_px_ = 0.0;
  double max_theta_ = 0.0;
  double focal_ = 0.0;  // equidistant/equisolid f, pixels
  double ocam_inverse_det_ = 1.0;
  Eigen::Matrix3d camera_to_body_ = Eigen::Matrix3d::Identity();
};

}  // namespace skyloc::dsp
