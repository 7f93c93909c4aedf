#pragma once
// Predicted noise of the decoded projector coordinate, per camera pixel, from
// the camera's measured noise and the pixel's own fringe mean A and
// modulation B (DecodeResult::mean and ::modulation, frame DN).
//
// Model (N-step phase shifting with equal steps 2 pi / N, least-squares
// phase, independent noise of variance sigma_I^2 in every sample; first order
// in sigma_I / B):
//   s = frame DN per sensor DN = 2^(frame_bit_depth - sensor_bit_depth)
//       (deeper sensors are MSB-aligned in 16-bit frames: exactly a shift)
//   q = quantisation step, frame DN = max(1, s) (rounding at the coarser of
//       the sensor's and the frame's depth)
//   sigma_I^2 = (s read)^2 + s A / gain + q^2 / 12          frame DN^2
//       read noise, shot noise (electrons = sensor DN * gain are Poisson),
//       rounding. The shot term of a sample is s I_k / gain; over the N
//       samples its weight in the phase averages to that of A exactly for
//       N >= 4 (for N = 3 a small part varies with the phase).
//   phase variance = 2 sigma_I^2 / (N B^2)                  rad^2
//   coordinate sigma = sqrt(phase variance) period / (2 pi) projector px
// B here is the true modulation. The decoder's B comes from the same noisy
// samples, and the noise adds its power: E[B_measured^2] = B^2 + 4
// sigma_I^2 / N. So B^2 is taken as B_measured^2 - 4 sigma_I^2 / N, but not
// below B_measured^2 / 2 (where the noise is that large the phase is close
// to random anyway; the floor keeps sigma falling as B rises). At the
// decoder's default threshold with the virtual scanner's noise this is a 2 %
// correction of sigma for N = 4; without it the darkest pixels' errors ran
// about 2 % over their prediction.
// Outside the model: gamma and other projector nonlinearity, defocus mixing
// across edges, interreflections, unwrapping errors (whole periods).
//
// Conventions: DN at the stated depth; projector pixels along the phase
// block's axis (the decoded coordinate, fpp/decoder.hpp).

#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"

namespace fpp {

// Measured on the camera (photon transfer), at the sensor's own depth.
struct CameraNoise {
    double read_noise_dn = 0; // Gaussian read noise, DN at sensor_bit_depth
    double gain_e_per_dn = 0; // electrons per DN at sensor_bit_depth; 0 = no shot noise term
    int sensor_bit_depth = 8; // 8..16; frames of deeper sensors are MSB-aligned 16-bit
    // Throws std::invalid_argument naming the field ("read_noise_dn",
    // "gain_e_per_dn", "sensor_bit_depth") for a value that is not finite,
    // negative, or (bit depth) outside 8..16. A caller that read the values
    // from a file reports them there with the file's name (InputError).
    void validate() const;
};

struct PhaseNoiseModel {
    CameraNoise camera;
    int frame_bit_depth = 8; // container depth of the decoded frames: 8 or 16
    int steps = 0;           // N of the phase block that sets the fine coordinate
    double period = 0;       // its period, projector pixels
};

// The model for the finest phase block (smallest period; the first of equal
// ones) of `axis` in `sequence`, the block whose phase gives the decoded
// coordinate's fine part. Throws std::invalid_argument if the axis has no
// phase block, `camera` is invalid or frame_bit_depth is not 8 or 16.
PhaseNoiseModel phase_noise_model(const Sequence& sequence, Axis axis, const CameraNoise& camera,
                                  int frame_bit_depth);

// Frame-DN variance of one sample at mean intensity `mean_dn` (frame DN):
// sigma_I^2 above.
double sample_variance_dn2(const PhaseNoiseModel& model, double mean_dn);

// Predicted standard deviation of the decoded projector coordinate along the
// model's axis, projector pixels, per camera pixel, from `modulation` (B) and
// `mean` (A) in frame DN (1 channel, the same size): NaN where B is not
// finite or <= 0 or A is NaN (A below 0 counts as 0). B^2 is corrected for
// the noise's share as above. `out` is resized to the camera size if needed
// (no allocation when it fits). Rows run on the process-wide pool. Throws
// std::invalid_argument for images of different sizes or channels, or an
// invalid model (camera, frame depth, steps < 3, period not > 0).
void coordinate_sigma(const Image<float>& modulation, const Image<float>& mean,
                      const PhaseNoiseModel& model, Image<float>& out);

} // namespace fpp
