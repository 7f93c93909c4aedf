#pragma once
// Which pose a calibration session should take next (internal to
// stereo_calibrate; trueness.hpp's PoseSuggestion). Candidates: the board's
// centre at 9 places over the camera image (a 3 x 3 grid at 20 %, 50 % and
// 80 % of each side), at the nearest, median and farthest depth of the
// session's board centres (never beyond them: the scanner's working
// volume is where the person put the boards), facing
// the camera or tilted 20, 35 or 45 degrees with each edge away; a
// candidate is kept when every corner shows in both devices with a margin
// and the board faces both within 70 degrees. Each is weighed by what it
// adds: its camera corners' information for the adjustment that holds the
// poses, its own pose marginalised (Schur complement), then
//   sigma^2 = s h^T (A + dA)^-1 h + g^T own g,  h = transfer^T g,
// with g the length's gradient (trueness_prediction.hpp). The projector's
// share (its stage, and the stage's response to the camera's) is held: a
// new pose's projector corners would only lower it further.

#include "calibration_covariance.hpp"
#include "fpp/calib/trueness.hpp"
#include "stereo/bundle_adjustment.hpp"

#include <Eigen/Dense>

#include <vector>

namespace fpp::calib::detail {

struct AdviceInputs {
    const RigState* state = nullptr;
    const CalibrationCovariance* covariance = nullptr;
    const Eigen::VectorXd* gradient = nullptr; // the length's, covariance order
    Size camera_size, projector_size;
    std::vector<Vec3> board; // the board's corners, board frame (mm)
    SessionDepths depths;    // board_centre_depths
    int count = 3;           // suggestions returned, best first
};

// The sigma of the length now (the same formula without a new pose), and
// the best candidates.
struct Advice {
    double sigma_mm = 0;
    std::vector<PoseSuggestion> next;
};
Advice suggest_poses(const AdviceInputs& in);

// The nearest, median and farthest camera Z of the used poses' board
// centres (the centre of `board`'s corners), mm.
SessionDepths board_centre_depths(const RigState& s, const std::vector<Vec3>& board,
                                  const std::vector<bool>& pose_used);

} // namespace fpp::calib::detail
