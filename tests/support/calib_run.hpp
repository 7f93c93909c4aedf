#pragma once
// fpp-calib run as a person runs it, for the command-line tests.
#include "test_support.hpp"

#include <filesystem>
#include <string>

namespace fpp::test {

// `fpp-calib args` (args already quoted), output captured through a log
// file in `scratch`.
inline ToolRun run_calib(const std::string& args, const std::filesystem::path& scratch) {
    return run_tool(calib_exe(), args, scratch);
}

} // namespace fpp::test
