// fpp-calib import TOOL FRAMES --out CAPTURE --projector WxH [tool parameters]
//
// A folder of another tool's camera frames becomes a capture set: the frames
// are copied as they are and capture.yaml describes their sequence in the
// tool's conventions (firmware/core/formats/imports.md). Exit status: 0
// written; 2 bad input (named file and field); 1 other errors.

#include "cli_util.hpp"
#include "commands.hpp"

#include "fpp/calib/capture_import.hpp"
#include "fpp/error.hpp"

#include <iostream>
#include <memory>

namespace fpp::calib {

namespace {

struct ImportArgs {
    std::string tool;
    std::string frames;
    std::string out;
    std::string projector;
    ImportOptions options;
    CLI::Option* direction_option = nullptr; // to know whether --direction was given
};

int run_import(ImportArgs args) {
    // OpenCV's Gray code always codes both axes.
    if (args.tool == "opencv" && args.options.codec == "graycode" &&
        args.direction_option->count() == 0)
        args.options.direction = "both";
    args.options.tool = parse_import_tool(args.tool);
    args.options.projector = parse_size_text(args.projector, "--projector");
    const CaptureManifest m = import_capture(args.frames, args.out, args.options);
    std::cout << "imported " << m.frames.size() << " frames (" << m.camera.width << "x"
              << m.camera.height << ") of " << args.tool << "'s " << args.options.codec << " into "
              << args.out << "/capture.yaml\n";
    return 0;
}

} // namespace

Action add_import_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<ImportArgs>(
        app, "import",
        "make a capture set from another tool's camera frames (SLStudio, SLMaster, OpenCV "
        "structured_light): the frames are copied as they are (PNG, TIFF or BMP, in the order "
        "of the last number in their names) and capture.yaml describes the tool's patterns; "
        "conventions and sources: firmware/core/formats/imports.md",
        run_import);
    cmd->add_option("tool", args->tool, "slstudio, slmaster or opencv")
        ->required()
        ->check(CLI::IsMember({"slstudio", "slmaster", "opencv"}));
    cmd->add_option("frames", args->frames, "folder of the camera frames")->required();
    cmd->add_option("--out", args->out, "capture-set folder to create (must not exist)")
        ->required();
    cmd->add_option("--projector", args->projector, "projector resolution WxH (e.g. 1920x1080)")
        ->required();
    cmd->add_option("--codec", args->options.codec,
                    "slstudio: 2x3, 3, nstep, 2p1, modulated, graycode, micro; slmaster: "
                    "complementary, shift-gray, three-frequency, interzone; "
                    "opencv: graycode, sinusoidal")
        ->required();
    args->direction_option =
        cmd->add_option("--direction", args->options.direction,
                        "coded axis: x (columns; SLStudio 'horizontal', SLMaster and OpenCV "
                        "SinusoidalPattern horizontal = false), y, or both (x then y; OpenCV's "
                        "Gray code is always both)")
            ->capture_default_str();
    cmd->add_option("--phases", args->options.slstudio_2x3_phases,
                    "slstudio 2x3: fringes across the projector (nPhases)")
        ->capture_default_str();
    cmd->add_option("--nstep-steps", args->options.slstudio_nstep_steps,
                    "slstudio nstep: phase steps (nSteps)")
        ->capture_default_str();
    cmd->add_option("--nstep-phases", args->options.slstudio_nstep_phases,
                    "slstudio nstep: fringes across the projector (nPhases)")
        ->capture_default_str();
    cmd->add_option("--modulated-phases", args->options.slstudio_modulated_phases_x,
                    "slstudio modulated: fringes across the projector's width (nPhaseX)")
        ->capture_default_str();
    cmd->add_option("--modulated-carrier-phases", args->options.slstudio_modulated_phases_y,
                    "slstudio modulated: carrier periods across its height (nPhaseY)")
        ->capture_default_str();
    cmd->add_option("--gray-bits-x", args->options.slstudio_gray_bits_x,
                    "slstudio graycode: column planes (Nhorz)")
        ->capture_default_str();
    cmd->add_option("--gray-bits-y", args->options.slstudio_gray_bits_y,
                    "slstudio graycode: row planes (Nvert)")
        ->capture_default_str();
    cmd->add_option("--steps", args->options.steps,
                    "slmaster: phase steps (shiftTime; default SLMaster's: 4, interzone 3)");
    cmd->add_option("--fringes", args->options.fringes,
                    "slmaster: fringes across the coded axis (nbrOfPeriods): a power of 2 "
                    "(complementary, shift-gray), the highest of the three (three-frequency, "
                    "default 32), a power of 4 (interzone, default 16)");
    cmd->add_option("--period", args->options.period,
                    "slmaster: or the fringe period in projector pixels (extent / fringes)");
    cmd->add_option("--shadow-images", args->options.shadow_images,
                    "opencv: where the white and black frames of getImagesForShadowMasks are: "
                    "last (after the patterns, as the module's capture sample), first, none")
        ->capture_default_str();
    cmd->add_option("--fringe-counts", args->options.fringe_counts,
                    "opencv sinusoidal: nbrOfPeriods of each set of three patterns, in capture "
                    "order, comma-separated (e.g. 1,4,16)")
        ->delimiter(',');
    cmd->add_option("--bit-depth", args->options.bit_depth,
                    "bits in use of 16-bit frames (9..16; default: found from the frames)");
    return action;
}

} // namespace fpp::calib
