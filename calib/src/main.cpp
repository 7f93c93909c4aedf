// fpp-calib: the host tool of the fpp scanner. Subcommands (each in cmd_*.cpp):
// simulate, simulate-session, demo (the virtual scanner); decode; stereo,
// hybrid, calibrate (calibration and coefficient tables); reconstruct (one
// camera with a table or calibration, or two cameras); evaluate; verify
// (a certified artefact, VDI/VDE 2634-2); correct (the depth scale from it);
// paper-experiments; response (projector response); import (other tools'
// captures); patterns (projector images for capture by hand); scanner-status,
// scanner-session, scanner-pull, scanner-push-table (a scanner over its HTTP
// API). Their use: README.md (and --help); file formats: firmware/core/formats/.

#include "commands.hpp"
#include "decode_outputs.hpp"

#include "fpp/error.hpp"

#include <iostream>
#include <map>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

int main(int argc, char** argv) {
#if defined(__GLIBC__)
    // The calibrations allocate and free the same large images pose after
    // pose (frames, decoded maps: 2 to 23 MB each at full size). glibc
    // would unmap each one and the next would fault its pages in again;
    // kept in the heap instead, 30 full-size poses calibrate in about 5 %
    // less time (measured) for 15 % more peak memory.
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
    CLI::App app{"fpp-calib: host tool of the fpp fringe-projection scanner"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "fpp-calib 0.1.0");

    std::map<CLI::App*, fpp::calib::Action> actions;
    auto add = [&](fpp::calib::Action (*adder)(CLI::App&)) {
        const auto before = app.get_subcommands({});
        auto action = adder(app);
        for (auto* sub : app.get_subcommands({}))
            if (std::find(before.begin(), before.end(), sub) == before.end())
                actions[sub] = std::move(action);
    };
    add(fpp::calib::add_simulate_command);
    add(fpp::calib::add_decode_command);
    add(fpp::calib::add_demo_command);
    add(fpp::calib::add_simulate_session_command);
    add(fpp::calib::add_stereo_command);
    add(fpp::calib::add_session_check_command);
    add(fpp::calib::add_reconstruct_command);
    add(fpp::calib::add_hybrid_command);
    add(fpp::calib::add_calibrate_command);
    add(fpp::calib::add_response_command);
    add(fpp::calib::add_evaluate_command);
    add(fpp::calib::add_verify_command);
    add(fpp::calib::add_correct_command);
    add(fpp::calib::add_paper_experiments_command);
    add(fpp::calib::add_import_command);
    add(fpp::calib::add_patterns_command);
    add(fpp::calib::add_scanner_status_command);
    add(fpp::calib::add_scanner_session_command);
    add(fpp::calib::add_scanner_pull_command);
    add(fpp::calib::add_scanner_push_table_command);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }

    try {
        for (auto* sub : app.get_subcommands())
            return actions.at(sub)();
    } catch (const fpp::InputError& e) {
        std::cerr << "fpp-calib: error: " << e.what() << "\n";
        return 2;
    } catch (const fpp::calib::DecodeRefused& e) {
        std::cerr << "fpp-calib: error: " << e.what() << "\n";
        return e.exit_code();
    } catch (const std::exception& e) {
        std::cerr << "fpp-calib: error: " << e.what() << "\n";
        return 1;
    }
    return 1;
}
