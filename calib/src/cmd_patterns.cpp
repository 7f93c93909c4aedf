// fpp-calib patterns --sequence SEQ --projector WxH --camera WxH --out DIR
//
// Writes the projector images of a sequence (one numbered file per frame,
// in capture order) and a capture.yaml template naming the camera frames to
// save, so a plain projector and camera can capture a set by hand.

#include "cli_util.hpp"
#include "commands.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"
#include "fpp/image_io.hpp"
#include "fpp/patterns.hpp"
#include "fpp/projector_response.hpp"

#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

namespace fpp::calib {

namespace fs = std::filesystem;

namespace {

struct PatternsArgs {
    std::string sequence;
    std::string projector;
    std::string camera;
    std::string out;
    std::string image_format = "png";
    double gamma = 0;
    std::string response;
};

std::string numbered(const char* prefix, int index, int count, const std::string& extension) {
    const int digits = count > 1000 ? 4 : (count > 100 ? 3 : 2);
    char text[64];
    std::snprintf(text, sizeof text, "%s%0*d.%s", prefix, digits, index, extension.c_str());
    return text;
}

const char* kReadme =
    "Patterns for a capture by hand (fpp-calib patterns).\n"
    "\n"
    "1. Show projector/pattern_NN files full screen on the projector, in order, at its\n"
    "   native resolution (no scaling, no colour management).\n"
    "2. For each one, save the camera's grey frame in this folder under the name that\n"
    "   capture.yaml lists at the same position (frames: frame_00.png, ...), 8- or\n"
    "   16-bit PNG, TIFF or BMP (rename the list if you save another format).\n"
    "3. Keep the camera's exposure fixed and the scene still. Then:\n"
    "   fpp-calib decode THIS_FOLDER --out decoded\n";

int run_patterns(const PatternsArgs& args) {
    const Size projector = parse_size_text(args.projector, "--projector");
    const Size camera = parse_size_text(args.camera, "--camera");
    const Sequence sequence = sequence_from_argument(args.sequence, projector);
    validate_sequence(sequence, projector, args.sequence);
    std::optional<GammaLut> lut;
    if (args.gamma > 0 && !args.response.empty())
        throw InputError("command line", "--gamma", "give --gamma or --response, not both");
    if (args.gamma > 0)
        lut = GammaLut::precompensate(args.gamma);
    if (!args.response.empty())
        lut = GammaLut::from_response(load_projector_response(args.response));

    const std::vector<Image<std::uint8_t>> images =
        render_sequence(sequence, projector, lut ? &*lut : nullptr);
    const int count = static_cast<int>(images.size());
    CaptureManifest m;
    m.camera = camera;
    m.projector = projector;
    m.sequence = sequence;
    for (int i = 0; i < count; ++i)
        m.frames.push_back(numbered("frame_", i, count, "png"));
    m.metadata_yaml = "{written_by: fpp-calib patterns, projector_images: projector}";
    const std::string yaml = manifest_to_yaml(m);

    write_folder_atomically(args.out, [&](const fs::path& temp) {
        fs::create_directory(temp / "projector");
        for (int i = 0; i < count; ++i) {
            const fs::path path =
                temp / "projector" / numbered("pattern_", i, count, args.image_format);
            if (args.image_format == "png") {
                Frame frame;
                frame.u8 = images[std::size_t(i)];
                write_png_synced(path, frame);
            } else {
                const auto& image = images[std::size_t(i)];
                const cv::Mat view(image.height(), image.width(), CV_8UC1,
                                   const_cast<std::uint8_t*>(image.row(0)),
                                   static_cast<std::size_t>(image.width()));
                if (!cv::imwrite(path.string(), view))
                    throw IoError(path, "cannot write the BMP file");
                fsync_path(path);
            }
        }
        fsync_path(temp / "projector");
        write_file_synced(temp / "capture.yaml", yaml);
        write_file_synced(temp / "README.txt", kReadme);
    });
    std::cout << "wrote " << count << " projector images to " << args.out
              << "/projector and the capture.yaml template to " << args.out << "\n";
    return 0;
}

} // namespace

Action add_patterns_command(CLI::App& app) {
    const auto [cmd, args, action] = add_command<PatternsArgs>(
        app, "patterns",
        "write the projector images of a sequence as numbered files (OUT/projector/pattern_NN) "
        "with a capture.yaml template naming the camera frames to save (frame_NN.png), so that "
        "a plain projector and camera can capture a set by hand: show each pattern full "
        "screen, save the camera frame under its name in OUT, then fpp-calib decode OUT",
        run_patterns);
    cmd->add_option("--sequence", args->sequence,
                    "a standard sequence name (gray-xy, ...) or a YAML file with a sequence: "
                    "list (firmware/core/formats/capture-set.md)")
        ->required();
    cmd->add_option("--projector", args->projector, "projector resolution WxH")->required();
    cmd->add_option("--camera", args->camera, "camera resolution WxH (for capture.yaml)")
        ->required();
    cmd->add_option("--out", args->out, "folder to create (must not exist)")->required();
    cmd->add_option("--image-format", args->image_format, "png or bmp")
        ->check(CLI::IsMember({"png", "bmp"}))
        ->capture_default_str();
    cmd->add_option("--gamma", args->gamma,
                    "pre-compensate a projector of response (level/255)^gamma");
    cmd->add_option("--response", args->response,
                    "or pre-compensate a measured projector response (fpp-calib response)");
    return action;
}

} // namespace fpp::calib
