#include "test_support.hpp"

#include <cstdlib>
#include <random>
#include <string>

namespace fpp::test {

std::filesystem::path shared_dir() {
    if (const char* env = std::getenv("FPP_SHARED_DIR"); env && *env) return env;
    return FPP_SHARED_DIR_DEFAULT;
}

std::filesystem::path dataset(const std::string& relative) {
    return shared_dir() / "datasets" / relative;
}

std::filesystem::path source_dir() { return FPP_SOURCE_DIR; }

bool in_ci() {
    const char* env = std::getenv("CI");
    return env && std::string(env) == "true";
}

TempDir::TempDir() {
    std::random_device rd;
    const auto base = std::filesystem::temp_directory_path();
    for (int attempt = 0; attempt < 100; ++attempt) {
        auto candidate = base / ("fpp-test-" + std::to_string(rd()));
        if (std::filesystem::create_directory(candidate)) {
            path_ = candidate;
            return;
        }
    }
    throw std::runtime_error("cannot create a temporary folder in " + base.string());
}

TempDir::~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
}

} // namespace fpp::test
