// Doty's FID on rendered calibration squares: every id and image point at several rotations
// (upright, tilted, upside down), missing fiducials, the collinear case, and look-alikes that
// must be rejected with the right reason.
#include "firmware/core/fiducial_id.hpp"

#include <doctest.h>

#include <cmath>

#include "tests/firmware/core/calibration_square_image.hpp"

using namespace kincal::core;
using kincal::test::Image;
using kincal::test::SquareView;

namespace {

constexpr int kSize = 150;
Image<kSize, kSize> g_img;
LabelerBuffers<kSize + 2, 64, 13, 8> g_buffers;
Blob g_blobs[64];
FidVerdict g_verdicts[64];

std::uint32_t label() {
  BlobLabeler labeler(g_buffers.memory());
  LabelerConfig config;
  config.polarity = Polarity::kDark;
  config.threshold = 120;
  REQUIRE(labeler.begin_frame(config, g_blobs) == LabelStatus::kOk);
  for (int y = 0; y < kSize; ++y) REQUIRE(labeler.push_row({g_img.px[y], kSize}) == LabelStatus::kOk);
  FrameSummary summary;
  REQUIRE(labeler.end_frame(summary) == LabelStatus::kOk);
  return summary.blobs;
}

FidStatus identify(std::uint32_t count, FidResult& result) {
  return identify_fiducials(FidModel{}, std::span<const Blob>(g_blobs, count), g_verdicts, result);
}

const IdentifiedFiducial* find_id(const FidResult& r, int id) {
  for (int i = 0; i < r.count; ++i)
    if (r.fiducials[static_cast<std::size_t>(i)].id == id) return &r.fiducials[static_cast<std::size_t>(i)];
  return nullptr;
}

// Fiducial `id` identified, at its image point in the view within 0.1 px.
void check_image_point(const FidResult& r, const SquareView& view, int id) {
  const IdentifiedFiducial* f = find_id(r, id);
  REQUIRE(f != nullptr);
  double x, y;
  kincal::test::fiducial_image_point(view, id, x, y);
  CHECK(std::fabs(f->x_px.to_double() - x) < 0.1);
  CHECK(std::fabs(f->y_px.to_double() - y) < 0.1);
}

}  // namespace

TEST_CASE("FID: every fiducial identified at its image point, at any rotation") {
  // Rational rotations of the square's +y axis: exact unit vectors.
  const double axes[][2] = {{0, -1}, {0.6, -0.8}, {-0.8, -0.6}, {0, 1}, {0.8, 0.6}, {-0.28, 0.96}};
  for (const auto& a : axes) {
    SquareView view{75.3, 74.6, a[0], a[1], 6.0};
    kincal::test::render_square(g_img, view);
    FidResult r;
    REQUIRE(identify(label(), r) == FidStatus::kOk);
    CHECK(r.count == 6);
    CHECK(r.orientation_from_marker);
    for (int id = 1; id <= 6; ++id) check_image_point(r, view, id);
    CHECK(std::fabs(r.y_axis_x.to_double() - a[0]) < 0.01);
    CHECK(std::fabs(r.y_axis_y.to_double() - a[1]) < 0.01);
    CHECK(std::fabs(r.x_axis_x.to_double() + a[1]) < 0.01);
    CHECK(std::fabs(r.x_axis_y.to_double() - a[0]) < 0.01);
    CHECK(std::fabs(r.fiducial_side_px.to_double() - 6.0) < 0.3);
  }
}

TEST_CASE("FID: missing fiducials — three non-collinear suffice, the prior orients without the marker") {
  SquareView view{75.0, 75.0, 0, 1, 6.0};  // +y along image +y: Doty's prior is right
  view.present[1] = false;                 // no corner marker
  view.present[5] = false;
  kincal::test::render_square(g_img, view);
  FidResult r;
  REQUIRE(identify(label(), r) == FidStatus::kOk);
  CHECK(r.count == 4);
  CHECK_FALSE(r.orientation_from_marker);
  CHECK(find_id(r, 2) != nullptr);
  CHECK(find_id(r, 3) != nullptr);
  CHECK(find_id(r, 6) != nullptr);
  CHECK(r.y_axis_y.to_double() > 0.99);

  // Only the centre and the two y-axis fiducials: collinear, the pose is not determined.
  view.present[3] = false;
  kincal::test::render_square(g_img, view);
  CHECK(identify(label(), r) == FidStatus::kCollinear);
  // Centre alone.
  view.present[2] = view.present[6] = false;
  kincal::test::render_square(g_img, view);
  CHECK(identify(label(), r) == FidStatus::kTooFewFiducials);
  // Nothing elongated at all.
  view.present[4] = false;
  view.present[2] = true;
  kincal::test::render_square(g_img, view);
  CHECK(identify(label(), r) == FidStatus::kNoCentre);
}

TEST_CASE("FID: look-alikes are rejected with their reason") {
  SquareView view{70.0, 70.0, 0, -1, 6.0};
  kincal::test::render_square(g_img, view);
  g_img.rect(120, 20, 125, 25, 40);    // right size and shape, nowhere a fiducial belongs
  g_img.rect(118, 110, 139, 131, 40);  // a large square: wrong area
  g_img.rect(20, 118, 31, 120, 40);    // the area of a fiducial, but a 12x3 bar: wrong shape
  g_img.rect(0, 60, 4, 66, 40);        // cut by the left border
  const std::uint32_t n = label();
  FidResult r;
  REQUIRE(identify(n, r) == FidStatus::kOk);
  CHECK(r.count == 6);
  int position = 0, area = 0, shape = 0, border = 0, identified = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    switch (g_verdicts[i]) {
      case FidVerdict::kRejectedPosition:
        ++position;
        CHECK(g_blobs[i].x_min_px == 120);
        break;
      case FidVerdict::kRejectedArea:
        ++area;
        CHECK(g_blobs[i].x_min_px == 118);
        break;
      case FidVerdict::kRejectedShape:
        ++shape;
        CHECK(g_blobs[i].x_min_px == 20);
        break;
      case FidVerdict::kRejectedBorder:
        ++border;
        break;
      case FidVerdict::kCentre:
      case FidVerdict::kPerimeter:
      case FidVerdict::kCorner:
        ++identified;
        break;
      default:
        break;
    }
  }
  CHECK(position == 1);
  CHECK(area == 1);
  CHECK(shape == 1);
  CHECK(border == 1);
  CHECK(identified == 6);
  // A shorter verdict span is refused.
  CHECK(identify_fiducials(FidModel{}, std::span<const Blob>(g_blobs, n), std::span<FidVerdict>(g_verdicts, 2), r) ==
        FidStatus::kVerdictsTooShort);
}

TEST_CASE("FID: on a strip, the square's own p3 and p5, not the neighbours' fiducials 2s beyond them") {
  // Doty's strip: the next squares' p3 and p5 lie 9s from this centre, 2s beyond its p5 and p3.
  // The centre blob drawn larger (8 x 14 px for 6 x 12: blur and threshold do that) makes s =
  // sqrt(area / 2) 7.5 px, so the 7s prediction falls nearer the neighbours'; the nearest to the
  // centre along the x axis is the square's own.
  SquareView view{70.0, 70.0, 0, -1, 6.0};  // +y up: p5 to the right
  kincal::test::render_square(g_img, view);
  g_img.rect(66, 63, 73, 76, 40);    // the enlarged centre
  g_img.rect(121, 67, 126, 72, 40);  // the right neighbour's p3, 9s to the right
  g_img.rect(13, 67, 18, 72, 40);    // the left neighbour's p5, 9s to the left
  FidResult r;
  REQUIRE(identify(label(), r) == FidStatus::kOk);
  for (const int id : {3, 5}) check_image_point(r, view, id);
}
