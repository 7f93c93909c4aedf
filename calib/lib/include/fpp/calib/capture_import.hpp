#pragma once
// Capture sets from other structured-light tools: a folder of camera frames
// plus the tool's parameters becomes a capture set (fpp-capture/2). Each
// tool's conventions (frame order, shift direction, period definition, which
// frames exist) and where they come from: firmware/core/formats/imports.md.
//
// Units: projector pixels, pixel centres on integers.

#include "fpp/capture_set.hpp"
#include "fpp/pattern_block.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace fpp::calib {

enum class ImportTool { slstudio, slmaster, opencv };

struct ImportOptions {
    ImportTool tool = ImportTool::slstudio;
    // slstudio: 2x3, 3, nstep, 2p1, modulated, graycode, micro;
    //   slmaster: complementary, shift-gray (a wrapping code: imports.md),
    //   three-frequency, interzone (four-level code, no white or black frame);
    // opencv: graycode, sinusoidal (SinusoidalPattern).
    std::string codec;
    Size projector;              // the projector's resolution, pixels
    std::string direction = "x"; // x (columns coded: SLStudio "horizontal", SLMaster
                                 // horizontal = false), y, or both (x then y)
    // SLStudio's compiled-in constants (change them if your build differs).
    int slstudio_2x3_phases = 16;         // CodecPhaseShift2x3 nPhases
    int slstudio_nstep_steps = 9;         // CodecPhaseShiftNStep nSteps
    int slstudio_nstep_phases = 8;        // CodecPhaseShiftNStep nPhases
    int slstudio_modulated_phases_x = 24; // CodecPhaseShiftModulated nPhaseX (fringes)
    int slstudio_modulated_phases_y = 16; // CodecPhaseShiftModulated nPhaseY (carrier)
    int slstudio_gray_bits_x = 10;        // CodecGrayCode Nhorz
    int slstudio_gray_bits_y = 6;         // CodecGrayCode Nvert
    // SLMaster's Params.
    int steps = 0;     // shiftTime; 0: SLMaster's default (4; interzone 3)
    int fringes = 0;   // nbrOfPeriods across the coded axis: a power of 2 (complementary,
                       // shift-gray: required), the highest of three (three-frequency;
                       // 0: 32), a power of 4 (interzone; 0: 16)
    double period = 0; // or the period in projector pixels (fringes = extent / period)
    // OpenCV's GrayCodePattern: where the white and black images of
    // getImagesForShadowMasks were captured: "last" (white, black after the
    // patterns, as the module's capture sample does), "first", or "none".
    std::string shadow_images = "last";
    // OpenCV's SinusoidalPattern: nbrOfPeriods of each set of three patterns,
    // in capture order (one set with 1, or sets the decoder can unwrap from).
    std::vector<int> fringe_counts;
    int bit_depth = 0; // manifest bit_depth for 16-bit frames (0 = found from the frames)
};

ImportTool parse_import_tool(const std::string& name); // std::invalid_argument
const char* to_string(ImportTool tool);

// The tool's pattern sequence for these options. Throws InputError naming
// `origin` (the frames folder) and the option ("codec", "fringes", ...) for an
// unknown codec or parameters the tool cannot have used.
Sequence import_sequence(const ImportOptions& options, const std::filesystem::path& origin);

// For each manifest frame, the index of the tool's frame (in capture order)
// it is: the identity except where the tool's frame order within a block
// differs from the spec's (SLStudio's modulated carrier shifts run the other
// way: its carrier frames 1 and 2 are listed swapped).
std::vector<int> import_frame_order(const ImportOptions& options, const Sequence& sequence);

// The image files of a folder (PNG, TIFF, BMP; case-insensitive), in capture
// order: by the last number in the file name when every name has one
// (frameSeq_2 before frameSeq_10), else by name.
std::vector<std::filesystem::path> list_frame_files(const std::filesystem::path& folder);

// Imports `frames` into a new capture-set folder `out` (which must not
// exist): the frames are copied as they are and capture.yaml describes them.
// Throws InputError naming the folder or the frame and the field: a wrong
// number of frames, frames of mixed sizes or depths, frames that are not
// grey, unknown codecs or parameters. Returns the manifest written.
CaptureManifest import_capture(const std::filesystem::path& frames,
                               const std::filesystem::path& out, const ImportOptions& options);

} // namespace fpp::calib
