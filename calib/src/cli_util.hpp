#pragma once
// Small helpers shared by the subcommands.

#include "commands.hpp"

#include "fpp/capture_set.hpp"
#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"
#include "fpp/point_cloud.hpp"

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>

namespace fpp::calib {

// A subcommand as its add_*_command declares it: the CLI11 subcommand, the
// arguments its options fill in, and the action run on them once parsed.
template <class Args> struct Command {
    CLI::App* cmd;
    std::shared_ptr<Args> args;
    Action action;
};

// Adds subcommand `name` to `app` (`description`: its line in --help) with
// default arguments; its action returns run(*args), the exit status.
template <class Args, class Run>
Command<Args> add_command(CLI::App& app, std::string name, std::string description, Run run) {
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand(std::move(name), std::move(description));
    return {cmd, args, [args, run] { return run(*args); }};
}

// An output file `option` names: its folder must exist and it must not be a
// folder (InputError naming the path and the option).
void check_output_path(const std::filesystem::path& path, const char* option);

// --threads, the same in every command that takes it: worker threads, 0 for
// all cores (the default shown is `threads`' value).
CLI::Option* add_threads_option(CLI::App& cmd, int& threads);
// --min-modulation, the decoder's threshold (DecodeOptions::min_modulation).
CLI::Option* add_min_modulation_option(CLI::App& cmd, double& min_modulation);

// A standard sequence name (fpp/sequences.hpp) or the path of a YAML file
// holding a `sequence:` list.
Sequence sequence_from_argument(const std::string& name_or_path, Size projector);

// "error against ground truth: RMS .. mm, max .. mm over .. points\n": the
// 3D error of `cloud` against a simulated capture's truth_xyz (camera frame,
// mm; pixels with both a point and a true surface, nothing removed); "" when
// the capture has no truth or nothing to compare.
std::string truth_comparison(const PointCloud& cloud, const CaptureSet& capture);

// "2.3 s": a duration for progress lines.
std::string seconds_text(double seconds);
// A size as the command line writes it: WIDTHxHEIGHT.
std::string size_text(Size s);
// "1280x1024" (or 1280X1024) -> Size, each side 1..65535; throws
// InputError("command line", option, ...) otherwise.
Size parse_size_text(const std::string& text, const char* option);

class Stopwatch {
public:
    double seconds() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    }

private:
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

} // namespace fpp::calib
