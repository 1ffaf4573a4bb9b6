// Intrinsic camera calibration (issue #6): cv::calibrateCamera over board detections, with what
// a user needs to judge the result -- one standard deviation per parameter, the RMS
// reprojection error of every view, the views left out and why, and warnings when the views do
// not constrain the model well.
//
// Model: OpenCV's pinhole with k1 k2 p1 p2 k3 (the firmware's model, firmware/core/
// camera_model.hpp), zero skew, pixel (0, 0) at the centre of the top-left pixel.
//
// Refused before any solve (CalibrationError): a detection that found another board than the
// one given (BoardDetection::larger_board, fitting_board; refuse_wrong_board's message names the
// view and the board text that fits), and images whose size differs from the first view's with
// a board (refuse_other_image_sizes names them: another camera or another resolution).
// Views left out (ViewReport::rejection): the detection's own reason ("pattern not found",
// "too few corners (N, at least M)"), "a near-duplicate of VIEW (the same corners within X px
// RMS)": a view whose corners lie within kDuplicateViewRms_px of an earlier used view's adds no
// information and, counted twice, makes the fit overconfident and biased (one image three times
// gave fx 750 for 600), "not needed: ..." beyond options.max_views views (a video gives
// thousands; the solve's cost grows with the cube of the views: 50, 100 and 200 views took 2,
// 11 and 76 s under ASan), where the max_views most spread are kept -- farthest-point sampling
// over where each puts the board (its centre in the image, its scale and its tilt, from the
// homography of its corners) -- or "an outlier: RMS ... and the other views' held-out RMS ...".
// The outlier gate (issue #43: rejection that never costs): after the first solve, a view whose
// RMS exceeds both options.outlier_over_median times the median view's RMS and
// options.outlier_floor_px is a candidate (its squared residuals are 9 times the typical view's:
// a bad detection, a moved or bent board -- or a close, frame-filling or steep view that reaches
// where the 5-parameter lens model fits worst, a good view with large residuals). Each candidate
// is judged by leave-views-out cross-validation, as identify's rejection gate judges rows: the
// other views, in options.outlier_folds folds, are each predicted (their corners, through a pose
// fitted to them by solvePnP) by the camera calibrated on the other folds with every candidate,
// and with every candidate but this one; the view is left out only when that lowers the judged
// views' held-out squared errors by at least two standard errors of their paired differences (a
// tie keeps it). Both held-out RMS are printed, for the views left out (ViewReport::rejection)
// and for the candidates kept (ViewReport::outlier_test). With too few other views for the folds
// (2 per fold, and min_views, at least 3, to calibrate on without a fold) candidates are kept,
// said so. Then the camera is solved once more without those left out (no second round). More
// than options.max_outlier_fraction of the views left out is refused: the views do not fit one
// camera. Cost: only with candidates, folds x (1 + candidates) calibrations of about
// (folds - 1) / folds of the views. (OpenCV's 13 sample views: median 0.16 px, largest 0.25 px;
// no candidate.)
// Warnings (IntrinsicCalibration::warnings; the calibration is still returned):
//   - fewer than options.recommended_views views used;
//   - the corners cover less than options.min_coverage of the image (cells of an 8 x 6 grid
//     holding at least one corner): distortion near the edges is extrapolated;
//   - no view tilts the board by options.min_tilt_rad or more: the focal length is then
//     strongly correlated with the board distance.
// Errors: CalibrationError when fewer than options.min_views views are usable; its message
// counts the views and lists each rejected one with its reason. Detections must carry their
// board coordinates (detect_board does).
// Uncertainty: the intrinsics' covariance with the view poses marginalised and the corner noise
// estimated from the residuals (host/camera/uncertainty.hpp); std_dev is its diagonal's root.
// describe() prints sigma and the worst-axis projection sigma over the image (its median and
// largest on a 16 x 12 grid, and where the largest is).
// Cost: one Levenberg-Marquardt solve in OpenCV, about a millisecond per view and iteration.
#pragma once

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "host/camera/board.hpp"
#include "host/camera/uncertainty.hpp"

namespace kincal::camera {

class CalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct CameraModel {
  cv::Size image_size;
  cv::Matx33d camera_matrix = cv::Matx33d::eye();  // fx 0 cx; 0 fy cy; 0 0 1 (px)
  std::array<double, 5> distortion{};              // k1 k2 p1 p2 k3
  cv::Mat distortion_mat() const;                  // 1 x 5, CV_64F, a copy
};

struct ViewReport {
  std::string view;
  bool used = false;
  std::string rejection;  // why not used; empty when used
  std::string detector;   // BoardDetection::detector
  int corners = 0;
  double rms_px = 0;                           // used views and outliers
  std::string outlier_test;                    // a candidate of the outlier gate kept: why, with both numbers
  cv::Vec3d camera_r_board, camera_t_board_m;  // rotation vector and translation, used views only
};

inline constexpr double kDuplicateViewRms_px = 1.0;

struct IntrinsicOptions {
  int min_views = 3;
  int recommended_views = 10;
  int max_views = 100;  // the most views solved on (see above)
  double min_coverage = 0.5;
  double min_tilt_rad = 20 * 3.14159265358979323846 / 180;
  int flags = 0;  // extra cv::CALIB_* flags (e.g. CALIB_FIX_K3)
  double outlier_over_median = 3;
  double outlier_floor_px = 0.5;
  double max_outlier_fraction = 0.25;
  int outlier_folds = 3;  // folds of the outlier gate's cross-validation (at least 2)
};

struct IntrinsicCalibration {
  CameraModel camera;
  std::array<double, 9> std_dev{};   // fx fy cx cy (px), k1 k2 p1 p2 k3: sqrt of uncertainty's diagonal
  IntrinsicsCovariance uncertainty;  // host/camera/uncertainty.hpp: poses marginalised, sigma from residuals
  double rms_px = 0;
  double coverage = 0;  // fraction of the 8 x 6 cells holding a corner
  int views_used = 0;
  std::vector<ViewReport> views;  // one per detection, in the order given
  std::vector<std::string> warnings;
};

// Throws CalibrationError when enough views found another board than the one given (a larger
// chessboard, another ChArUco sheet or AprilGrid), naming the first view that measured the size
// most views measured (BoardDetection::fitting_board) and that board text, or the first such
// view when none could measure it; returns otherwise. Enough (issue #43: a gate must not refuse
// valid data on one view's say): every view showing a board shows another one, or at least
// kMinWrongBoardViews of them do and they are at least 1 / kWrongBoardShare of the views showing
// a board (found, or another board). Fewer are left out as not found, with their reason. (A board
// of the wrong size is seen in most views: given 8x6 for OpenCV's 9x6 sample board, 463 of its 546
// real views and variants (tests/host/camera/real_corpus.hpp) showed 9x6, 23 took 8x6; 9x5: 107
// and 33; 4x3: 115 and 40 -- measured with 90 % of a ring's squares to agree.) Stereo and
// hand-eye calibration use it too.
inline constexpr long kMinWrongBoardViews = 2;
inline constexpr long kWrongBoardShare = 4;
void refuse_wrong_board(const std::vector<BoardDetection>& detections);
// For a message refusing too few views: "\n  N of M views show a chessboard:9x6:0.025
// board: give --board chessboard:9x6:0.025?", the board most views show where the given one was
// not found (BoardDetection::seen_board); "" when none shows one.
std::string seen_board_hint(const std::vector<BoardDetection>& detections);
// Throws CalibrationError naming the images (up to five) whose size is not `expected`, the size
// of `whose`; images without a size (unread) are not judged.
void refuse_other_image_sizes(const std::vector<BoardDetection>& detections, cv::Size expected,
                              const std::string& whose);

IntrinsicCalibration calibrate_intrinsics(const std::vector<BoardDetection>& detections,
                                          const IntrinsicOptions& options = {});

// A text report: parameters with their standard deviations, RMS, each view, the warnings.
std::string describe(const IntrinsicCalibration& calibration);

}  // namespace kincal::camera
