#include "host/sim/render.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <mutex>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace kincal::sim {

namespace {

constexpr int kMaxImageSidePx = 8192;
constexpr int kMaxSupersampling = 8;
constexpr double kMaxBlurSigmaPx = 20.0;
constexpr int kMaxUndistortIterations = 50;
constexpr double kUndistortTolerancePx = 1e-6;
constexpr std::size_t kRayCacheEntries = 8;

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("render_plane: " + what); }

void check_finite(double v, const char* field) {
  if (!std::isfinite(v)) fail(std::string(field) + " is not finite");
}

void validate(const CameraSpec& c) {
  if (c.width_px < 1 || c.width_px > kMaxImageSidePx) {
    fail("CameraSpec.width_px " + std::to_string(c.width_px) + " outside 1..8192");
  }
  if (c.height_px < 1 || c.height_px > kMaxImageSidePx) {
    fail("CameraSpec.height_px " + std::to_string(c.height_px) + " outside 1..8192");
  }
  check_finite(c.fx_px, "CameraSpec.fx_px");
  check_finite(c.fy_px, "CameraSpec.fy_px");
  if (c.fx_px <= 0) fail("CameraSpec.fx_px must be positive");
  if (c.fy_px <= 0) fail("CameraSpec.fy_px must be positive");
  check_finite(c.cx_px, "CameraSpec.cx_px");
  check_finite(c.cy_px, "CameraSpec.cy_px");
  for (double k : c.distortion) check_finite(k, "CameraSpec.distortion");
}

void validate(const ImagingConditions& i) {
  check_finite(i.exposure_dn, "ImagingConditions.exposure_dn");
  if (i.exposure_dn < 0) fail("ImagingConditions.exposure_dn is negative");
  check_finite(i.black_level_dn, "ImagingConditions.black_level_dn");
  if (i.black_level_dn < 0) fail("ImagingConditions.black_level_dn is negative");
  check_finite(i.blur_sigma_px, "ImagingConditions.blur_sigma_px");
  if (i.blur_sigma_px < 0 || i.blur_sigma_px > kMaxBlurSigmaPx) fail("ImagingConditions.blur_sigma_px outside 0..20");
  check_finite(i.gradient, "ImagingConditions.gradient");
  if (std::abs(i.gradient) > 1) fail("ImagingConditions.gradient outside -1..1");
  check_finite(i.vignetting, "ImagingConditions.vignetting");
  if (i.vignetting < 0 || i.vignetting >= 1) fail("ImagingConditions.vignetting outside [0, 1)");
  check_finite(i.read_noise_dn, "ImagingConditions.read_noise_dn");
  if (i.read_noise_dn < 0) fail("ImagingConditions.read_noise_dn is negative");
  check_finite(i.shot_noise_gain, "ImagingConditions.shot_noise_gain");
  if (i.shot_noise_gain < 0) fail("ImagingConditions.shot_noise_gain is negative");
  if (i.supersampling < 1 || i.supersampling > kMaxSupersampling) {
    fail("ImagingConditions.supersampling " + std::to_string(i.supersampling) + " outside 1..8");
  }
}

// OpenCV's distortion of normalized coordinates, with its Jacobian.
Eigen::Vector2d distort(const std::array<double, 5>& k, const Eigen::Vector2d& p, Eigen::Matrix2d* jacobian) {
  const double x = p.x(), y = p.y();
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (k[0] + r2 * (k[1] + r2 * k[4]));
  const double p1 = k[2], p2 = k[3];
  const Eigen::Vector2d d(x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
                          y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y);
  if (jacobian != nullptr) {
    const double dradial_dr2 = k[0] + r2 * (2 * k[1] + 3 * r2 * k[4]);
    (*jacobian)(0, 0) = radial + 2 * x * x * dradial_dr2 + 2 * p1 * y + 6 * p2 * x;
    (*jacobian)(0, 1) = 2 * x * y * dradial_dr2 + 2 * p1 * x + 2 * p2 * y;
    (*jacobian)(1, 0) = 2 * x * y * dradial_dr2 + 2 * p1 * x + 2 * p2 * y;
    (*jacobian)(1, 1) = radial + 2 * y * y * dradial_dr2 + 6 * p1 * y + 2 * p2 * x;
  }
  return d;
}

// The undistorted normalized coordinates of every pixel corner (pixel centre +- 0.5) of the
// image grown by `margin_px` on each side: (width + 2 margin + 1) x (height + 2 margin + 1).
// Sub-pixel rays are bilinear in these corners: the undistortion's curvature over one pixel
// moves a ray by about 1 / (8 f) px.
struct CornerRays {
  CameraSpec camera;
  int margin_px = 0;
  int cols = 0, rows = 0;
  std::vector<Eigen::Vector2d> xy;
  const Eigen::Vector2d& at(int col, int row) const {
    return xy[static_cast<std::size_t>(row) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(col)];
  }
};

bool same_camera(const CameraSpec& a, const CameraSpec& b) {
  return a.width_px == b.width_px && a.height_px == b.height_px && a.fx_px == b.fx_px && a.fy_px == b.fy_px &&
         a.cx_px == b.cx_px && a.cy_px == b.cy_px && a.distortion == b.distortion;
}

// Newton's method on OpenCV's distortion, bounded and checked: the answer must re-distort to the
// pixel within kUndistortTolerancePx, on the side of the distortion where it is one-to-one.
Eigen::Vector2d undistort(const CameraSpec& c, double u_px, double v_px) {
  const Eigen::Vector2d target((u_px - c.cx_px) / c.fx_px, (v_px - c.cy_px) / c.fy_px);
  Eigen::Vector2d p = target;
  Eigen::Matrix2d j;
  for (int i = 0; i < kMaxUndistortIterations; ++i) {
    const Eigen::Vector2d r = distort(c.distortion, p, &j) - target;
    if (std::abs(r.x() * c.fx_px) < 1e-3 * kUndistortTolerancePx &&
        std::abs(r.y() * c.fy_px) < 1e-3 * kUndistortTolerancePx) {
      break;
    }
    if (!(std::abs(j.determinant()) > 1e-12)) break;
    const Eigen::Vector2d step = j.partialPivLu().solve(r);
    // Damped: never jump further than the point's own distance (keeps divergent cases bounded).
    const double limit = std::max(0.5, p.norm());
    p -= step.norm() > limit ? (limit / step.norm()) * step : step;
  }
  const Eigen::Vector2d r = distort(c.distortion, p, &j) - target;
  if (!(std::abs(r.x() * c.fx_px) < kUndistortTolerancePx && std::abs(r.y() * c.fy_px) < kUndistortTolerancePx) ||
      !(j.determinant() > 0)) {
    fail("CameraSpec.distortion cannot be inverted at pixel (" + std::to_string(u_px) + ", " + std::to_string(v_px) +
         "): the distortion folds or the iteration did not converge");
  }
  return p;
}

std::shared_ptr<const CornerRays> compute_rays(const CameraSpec& c, int margin_px) {
  auto rays = std::make_shared<CornerRays>();
  rays->camera = c;
  rays->margin_px = margin_px;
  rays->cols = c.width_px + 2 * margin_px + 1;
  rays->rows = c.height_px + 2 * margin_px + 1;
  rays->xy.resize(static_cast<std::size_t>(rays->cols) * static_cast<std::size_t>(rays->rows));
  std::atomic<bool> failed{false};
  std::string failure;
  std::mutex failure_mutex;
  cv::parallel_for_(cv::Range(0, rays->rows), [&](const cv::Range& range) {
    for (int row = range.start; row < range.end; ++row) {
      for (int col = 0; col < rays->cols; ++col) {
        const double u = col - margin_px - 0.5, v = row - margin_px - 0.5;
        try {
          rays->xy[static_cast<std::size_t>(row) * static_cast<std::size_t>(rays->cols) +
                   static_cast<std::size_t>(col)] = undistort(c, u, v);
        } catch (const std::invalid_argument& e) {
          const std::lock_guard lock(failure_mutex);
          if (!failed.exchange(true)) failure = e.what();
          return;
        }
      }
    }
  });
  if (failed) throw std::invalid_argument(failure);
  return rays;
}

// A small process-wide cache of the most recently used cameras, guarded by a mutex.
std::shared_ptr<const CornerRays> rays_for(const CameraSpec& c, int margin_px) {
  static std::mutex mutex;
  static std::vector<std::shared_ptr<const CornerRays>> cache;  // most recent last
  {
    const std::lock_guard lock(mutex);
    for (auto it = cache.begin(); it != cache.end(); ++it) {
      if ((*it)->margin_px == margin_px && same_camera((*it)->camera, c)) {
        std::shared_ptr<const CornerRays> hit = *it;
        cache.erase(it);
        cache.push_back(hit);
        return hit;
      }
    }
  }
  std::shared_ptr<const CornerRays> fresh = compute_rays(c, margin_px);
  const std::lock_guard lock(mutex);
  if (cache.size() >= kRayCacheEntries) cache.erase(cache.begin());
  cache.push_back(fresh);
  return fresh;
}

// Illumination times vignetting at pixel (u, v): 1 + gradient (u - cx) / width, times a cos^4
// fall-off 1 / (1 + r^2 / r0^2)^2 scaled so the farthest image corner gets 1 - vignetting.
struct Illumination {
  double gradient_per_px = 0, cx = 0, cy = 0, inv_r0_sq = 0;
  Illumination(const CameraSpec& c, const ImagingConditions& i)
      : gradient_per_px(i.gradient / c.width_px), cx(c.cx_px), cy(c.cy_px) {
    double corner_sq = 0;
    for (double u : {-0.5, c.width_px - 0.5}) {
      for (double v : {-0.5, c.height_px - 0.5})
        corner_sq = std::max(corner_sq, (u - cx) * (u - cx) + (v - cy) * (v - cy));
    }
    if (i.vignetting > 0 && corner_sq > 0) inv_r0_sq = (1 / std::sqrt(1 - i.vignetting) - 1) / corner_sq;
  }
  double gain(double u, double v) const {
    const double q = 1 + ((u - cx) * (u - cx) + (v - cy) * (v - cy)) * inv_r0_sq;
    return (1 + gradient_per_px * (u - cx)) / (q * q);
  }
};

// Sub-pixel sample positions in [0, 1)^2: an n x n grid sheared so that all n^2 samples have
// distinct x and distinct y (an "n-rooks" lattice). A plain grid sees an edge along a pixel row
// or column in only n steps of coverage, which moves such edges by up to 1 / (2n) px (measured:
// chessboard corners 0.07 px off at n = 3); the sheared one sees n^2 steps.
std::vector<std::pair<double, double>> sample_offsets(int n) {
  std::vector<std::pair<double, double>> offsets;
  const double n2 = static_cast<double>(n) * n;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) offsets.emplace_back((i * n + j + 0.5) / n2, (j * n + i + 0.5) / n2);
  }
  return offsets;
}

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

}  // namespace

cv::Mat render_plane(const CameraSpec& camera, const Eigen::Isometry3d& camera_T_target, const PlanarTarget& target,
                     const ImagingConditions& conditions) {
  validate(camera);
  validate(conditions);
  if (!camera_T_target.matrix().allFinite()) fail("camera_T_target is not finite");
  if (!target.reflectance) fail("PlanarTarget.reflectance is empty");

  // Margin: the blur's support, so that border pixels are blurred from rendered neighbours.
  const int margin = conditions.blur_sigma_px > 0 ? static_cast<int>(std::ceil(3 * conditions.blur_sigma_px)) : 0;
  const std::shared_ptr<const CornerRays> rays = rays_for(camera, margin);
  const int w = camera.width_px + 2 * margin, h = camera.height_px + 2 * margin;

  // A camera ray (x, y, 1) in the target frame: origin o, direction a x + b y + c.
  const Eigen::Isometry3d target_T_camera = camera_T_target.inverse();
  const Eigen::Matrix3d r = target_T_camera.linear();
  const double ox = target_T_camera.translation().x(), oy = target_T_camera.translation().y(),
               oz = target_T_camera.translation().z();
  const double ax = r(0, 0), ay = r(1, 0), az = r(2, 0), bx = r(0, 1), by = r(1, 1), bz = r(2, 1), cx = r(0, 2),
               cy = r(1, 2), cz = r(2, 2);

  const std::vector<std::pair<double, double>> offsets = sample_offsets(conditions.supersampling);
  const double inv_samples = 1.0 / static_cast<double>(offsets.size());
  const Illumination light(camera, conditions);
  cv::Mat radiance(h, w, CV_32F);
  std::atomic<int> non_finite_row{-1};
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& range) {
    for (int row = range.start; row < range.end; ++row) {
      float* out = radiance.ptr<float>(row);
      for (int col = 0; col < w; ++col) {
        // Plain doubles: this loop runs supersampling^2 times per pixel.
        const Eigen::Vector2d& p00 = rays->at(col, row);
        const Eigen::Vector2d& p10 = rays->at(col + 1, row);
        const Eigen::Vector2d& p01 = rays->at(col, row + 1);
        const Eigen::Vector2d& p11 = rays->at(col + 1, row + 1);
        double sum = 0;
        for (const auto& [fx, fy] : offsets) {
          const double lx = p00.x() + fy * (p01.x() - p00.x()), ly = p00.y() + fy * (p01.y() - p00.y());
          const double rx = p10.x() + fy * (p11.x() - p10.x()), ry = p10.y() + fy * (p11.y() - p10.y());
          const double x = lx + fx * (rx - lx), y = ly + fx * (ry - ly);
          const double dx = ax * x + bx * y + cx, dy = ay * x + by * y + cy, dz = az * x + bz * y + cz;
          const double s = -oz / dz;
          if (!(s > 0) || !std::isfinite(s)) continue;  // the ray misses the plane: black
          sum += target.reflectance(ox + s * dx, oy + s * dy);
        }
        const double u = col - margin, v = row - margin;
        const double value = conditions.exposure_dn * light.gain(u, v) * sum * inv_samples;
        if (!std::isfinite(value)) non_finite_row = row - margin;
        out[col] = static_cast<float>(value);
      }
    }
  });
  if (non_finite_row >= 0) {
    fail("PlanarTarget.reflectance returned a non-finite value in image row " + std::to_string(non_finite_row.load()));
  }
  if (margin > 0) {
    cv::GaussianBlur(radiance, radiance, cv::Size(2 * margin + 1, 2 * margin + 1), conditions.blur_sigma_px,
                     conditions.blur_sigma_px, cv::BORDER_REPLICATE);
  }

  cv::Mat image(camera.height_px, camera.width_px, CV_8UC1);
  const bool noisy = conditions.read_noise_dn > 0 || conditions.shot_noise_gain > 0;
  cv::parallel_for_(cv::Range(0, camera.height_px), [&](const cv::Range& range) {
    for (int row = range.start; row < range.end; ++row) {
      // One generator per row, seeded from (seed, row): the same bits whatever the threading.
      std::mt19937_64 rng(splitmix64(conditions.seed ^ splitmix64(static_cast<std::uint64_t>(row))));
      std::normal_distribution<double> unit(0.0, 1.0);
      const float* in = radiance.ptr<float>(row + margin) + margin;
      std::uint8_t* out = image.ptr<std::uint8_t>(row);
      for (int col = 0; col < camera.width_px; ++col) {
        const double signal = std::max(0.0, static_cast<double>(in[col]));
        double value = conditions.black_level_dn + signal;
        if (noisy) {
          value +=
              std::sqrt(conditions.read_noise_dn * conditions.read_noise_dn + conditions.shot_noise_gain * signal) *
              unit(rng);
        }
        out[col] = cv::saturate_cast<std::uint8_t>(value);
      }
    }
  });
  return image;
}

PlanarTarget chessboard(int inner_cols, int inner_rows, double square_m) {
  if (inner_cols < 2) throw std::invalid_argument("chessboard: inner_cols " + std::to_string(inner_cols) + " < 2");
  if (inner_rows < 2) throw std::invalid_argument("chessboard: inner_rows " + std::to_string(inner_rows) + " < 2");
  if (!(square_m > 0) || !std::isfinite(square_m)) {
    throw std::invalid_argument("chessboard: square_m must be positive and finite");
  }
  // Squares (i, j), i = -1..inner_cols-1, j = -1..inner_rows-1, span [i s, (i+1) s] x [j s, (j+1) s];
  // square (-1, -1) is black. One white square of border around them, grey beyond.
  return PlanarTarget{[inner_cols, inner_rows, square_m](double x_m, double y_m) {
    const double i = std::floor(x_m / square_m), j = std::floor(y_m / square_m);
    if (i < -2 || j < -2 || i > inner_cols || j > inner_rows) return 0.5;
    if (i < -1 || j < -1 || i > inner_cols - 1 || j > inner_rows - 1) return 1.0;
    return std::fmod(std::abs(i + j), 2.0) == 0 ? 0.0 : 1.0;
  }};
}

PlanarTarget texture(const cv::Mat& grey, double metres_per_pixel, double outside) {
  if (grey.empty() || grey.type() != CV_8UC1)
    throw std::invalid_argument("texture: grey must be a non-empty CV_8UC1 image");
  if (!(metres_per_pixel > 0) || !std::isfinite(metres_per_pixel)) {
    throw std::invalid_argument("texture: metres_per_pixel must be positive and finite");
  }
  if (!(outside >= 0 && outside <= 1)) throw std::invalid_argument("texture: outside must be in [0, 1]");
  auto image = std::make_shared<const cv::Mat>(grey.clone());
  return PlanarTarget{[image, metres_per_pixel, outside](double x_m, double y_m) {
    // Nearest texel: a printed texture is piecewise constant.
    const double col = std::floor(x_m / metres_per_pixel + 0.5), row = std::floor(y_m / metres_per_pixel + 0.5);
    if (col < 0 || row < 0 || col >= image->cols || row >= image->rows) return outside;
    return image->at<std::uint8_t>(static_cast<int>(row), static_cast<int>(col)) / 255.0;
  }};
}

std::vector<cv::Point2d> project_points(const CameraSpec& camera, const Eigen::Isometry3d& camera_T_target,
                                        std::span<const Eigen::Vector3d> points_target_m) {
  validate(camera);
  if (!camera_T_target.matrix().allFinite()) fail("camera_T_target is not finite");
  std::vector<cv::Point3d> points;
  for (const Eigen::Vector3d& p : points_target_m) points.emplace_back(p.x(), p.y(), p.z());
  std::vector<cv::Point2d> pixels;
  if (points.empty()) return pixels;
  cv::Mat rotation, rvec;
  cv::eigen2cv(Eigen::Matrix3d(camera_T_target.linear()), rotation);
  cv::Rodrigues(rotation, rvec);
  const Eigen::Vector3d t = camera_T_target.translation();
  const cv::Matx33d k(camera.fx_px, 0, camera.cx_px, 0, camera.fy_px, camera.cy_px, 0, 0, 1);
  const std::vector<double> distortion(camera.distortion.begin(), camera.distortion.end());
  cv::projectPoints(points, rvec, cv::Vec3d(t.x(), t.y(), t.z()), k, distortion, pixels);
  return pixels;
}

Eigen::Isometry3d facing_camera(const Eigen::Vector3d& point_camera_m, double tilt_x_rad, double tilt_y_rad,
                                const Eigen::Vector3d& target_point_m, Facing facing) {
  Eigen::Isometry3d camera_T_target = Eigen::Isometry3d::Identity();
  const double turn_rad = facing == Facing::kZToward ? std::numbers::pi : 0.0;
  camera_T_target.linear() =
      (Eigen::AngleAxisd(turn_rad, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(tilt_x_rad, Eigen::Vector3d::UnitX()) *
       Eigen::AngleAxisd(tilt_y_rad, Eigen::Vector3d::UnitY()))
          .toRotationMatrix();
  camera_T_target.translation() = point_camera_m - camera_T_target.linear() * target_point_m;
  return camera_T_target;
}

}  // namespace kincal::sim
