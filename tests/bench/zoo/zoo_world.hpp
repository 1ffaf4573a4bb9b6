// The zoo's simulated world (issue #41): a truth (the URDF's chain with an error class, the
// measuring device's registration, the measured point or frame on the flange), the instruments'
// noise, reachable configurations, and the datasets in the format `kincal identify --data` reads
// (README "Formats and frames"), with or without a planted mistake.
#pragma once

#include <random>
#include <string>
#include <vector>

#include "zoo_chain.hpp"

namespace zoo {

enum class Instrument { tracker_point, tracker_6dof, mocap, camera };
enum class ErrorClass { precise, service, scaled, coupled };
enum class Mistake {
  none,
  mirrored,
  joints_swapped,
  positions_swapped,
  validate_is_train,
  mm_as_m,
  deg_as_rad,
  out_of_step,        // each row's position is the next row's (the logs joined a row apart)
  instrument_moved,   // from 60 % of the rows on, measured from a device turned 1 deg and moved 5 mm
  joint_reversed,     // the second revolute joint counted the other way round by the controller
  joint_zero_turned,  // the third revolute joint's zero a quarter turn from the URDF's
  inches,             // positions exported in inches
  marker_moved,       // from 60 % of the rows on, the reflector, marker or board 40 mm from where it was
};

const char* name(Instrument i);
const char* name(ErrorClass c);
const char* name(Mistake m);
bool measures_pose(Instrument i);

struct Truth {
  ChainErrors errors;
  Pose device_T_root;    // the device frame: a tracker's, a mocap's or the camera's (z its line of sight)
  Pose flange_T_marker;  // the reflector, marker, 6-DoF target or board: no link of the URDF
  Instrument instrument = Instrument::tracker_point;
  Eigen::Vector3d position_sigma_m;  // per axis of the device frame
  double rotation_sigma_rad = 0.0;
  Eigen::Vector3d workspace_centre_root;  // where the device looks
  // Per joint: a compliance on a joint gravity barely loads (below a tenth of the most loaded
  // joint's torque), which the oracle is given as it is given the masses: fitted by plain least
  // squares, a deflection that small only adds noise to the reference.
  std::vector<bool> compliance_known;
  explicit Truth(std::size_t joints) : errors(joints), compliance_known(joints, false) {}
};

// One reading: the controller's joint values, the noisy measurement and the truth it came from, in
// the device frame.
struct Row {
  std::vector<double> q;
  Pose measured, truth;
};

// How far a non-default zoo moves its truths (zoo_bench --error-scale, --noise-scale): every error
// class's geometric errors and every instrument's noise times these.
struct TruthScales {
  double errors = 1.0;
  double noise = 1.0;
};

Truth make_truth(const Chain& chain, Instrument instrument, ErrorClass error_class, std::mt19937& rng,
                 const TruthScales& scales);

// Slides the flange along and turns it about the last axis to where the nominal chain puts it
// relative to the last two axes' common normal: what no measurement on the last body can tell from
// the measured point's offset, so the truth's place for it and the only one a fit can have (the
// oracle's, at the TCP). Throws std::runtime_error for a chain whose last two joints are not two
// revolute joints with axes at least 0.1 rad from parallel.
void place_flange_as_nominal(Truth& t, const Chain& chain);

// n configurations within the joint limits with the flange above the base and the point in the
// device's sight (a 40 deg cone for trackers, the field of view and a board facing the camera).
std::vector<std::vector<double>> configurations(const Chain& chain, const Truth& truth, int n, std::mt19937& rng);

// The true measured point/frame in the device frame (no noise).
Pose measured_truth(const Chain& chain, const Truth& truth, const std::vector<double>& q);
std::vector<Row> measure(const Chain& chain, const Truth& truth, const std::vector<std::vector<double>>& qs,
                         std::mt19937& rng);

// The dataset CSV (q1..qN,x,y,z[,qw,qx,qy,qz][,cxx..czz],id), ids `<id_prefix><row>`, with the
// mistake written into it (validate_is_train changes no file; out_of_step drops the last row).
std::string dataset_csv(const Chain& chain, const Truth& truth, const std::vector<Row>& rows,
                        const std::string& id_prefix, Mistake mistake);

}  // namespace zoo
