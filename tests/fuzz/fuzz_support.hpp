#pragma once
// What every harness shares: a private temporary folder for readers that take
// a path, and the one place that decides which exceptions are the project's
// declared answers to bad input. Anything else (another exception type, a
// crash, a sanitizer report) escapes to libFuzzer, which reports it.
#include "fpp/error.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace fpp::fuzz {

// Created on first use, removed at exit (one per fuzzing process: libFuzzer's
// workers each get their own pid).
class ScratchDir {
public:
    ScratchDir() {
        path_ = std::filesystem::temp_directory_path() / ("fpp-fuzz-" + std::to_string(::getpid()));
        std::filesystem::create_directories(path_);
    }
    ~ScratchDir() {
        std::error_code ignored;
        std::filesystem::remove_all(path_, ignored);
    }
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

inline const std::filesystem::path& scratch() {
    static const ScratchDir dir;
    return dir.path();
}

inline std::string as_text(const std::uint8_t* data, std::size_t size) {
    return std::string(reinterpret_cast<const char*>(data), size);
}

// Writes the fuzzer's bytes to `path` (truncating); returns the path.
inline std::filesystem::path write_input(const std::filesystem::path& path,
                                         const std::uint8_t* data, std::size_t size) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (!out)
        throw std::runtime_error("fuzz harness: cannot write " + path.string());
    return path;
}

// Runs `read`; the declared errors for bad input (InputError, which
// CameraPairFileError derives from, and IoError) are the expected outcome,
// everything else propagates.
template <class Read> void expect_declared_errors(Read&& read) {
    try {
        read();
    } catch (const InputError&) {
    } catch (const IoError&) {
    }
}

} // namespace fpp::fuzz
