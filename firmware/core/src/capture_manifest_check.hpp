#pragma once
// Validation of parsed capture manifests and sequences (fpp-capture/1 and /2,
// firmware/core/formats/capture-set.md). Shared by the YAML reader (which
// passes the YAML line of each field so that messages point into the file),
// the writer and the folder reader. Internal to fpp_core.

#include "fpp/capture_set.hpp"

#include <filesystem>
#include <map>
#include <string>

namespace fpp::capture_check {

inline constexpr int kMaxImageSide = 65535; // the frame readers refuse larger frames too
inline constexpr int kMaxGrayBits = 30;     // code steps are numbered in an int
inline constexpr const char* kManifestName = "capture.yaml";

class Checker {
public:
    Checker(std::filesystem::path origin, const std::map<std::string, int>* lines)
        : origin_(std::move(origin)), lines_(lines) {}

    [[noreturn]] void fail(const std::string& field, const std::string& message) const;
    const std::filesystem::path& origin() const { return origin_; }

private:
    // " (line N)" of the field or of its nearest parent that has a line.
    std::string where(std::string field) const;

    std::filesystem::path origin_;
    const std::map<std::string, int>* lines_;
};

// "sequence[3].period"
std::string block_field(std::size_t index, const char* key);

// A gray block whose period is the period of a phase block on its axis
// indexes that block's periods; any other gray block codes the axis alone.
bool gray_indexes_phase(const Sequence& sequence, const GrayBlock& gray);
// True when the sequence (or manifest) uses anything of fpp-capture/2.
bool uses_version_2(const Sequence& sequence);
bool uses_version_2(const CaptureManifest& manifest);

// Checks that need no projector size. `version` is the file's format
// version (1 or 2); a version-1 file cannot hold a code-only gray block.
void check_sequence_alone(const Sequence& sequence, const Checker& check, int version);
void check_sequence_on_projector(const Sequence& sequence, Size projector, const Checker& check,
                                 int version);
void check_size(const Size& size, const std::string& field, const Checker& check);
// Everything in a manifest except the frame files themselves.
void check_manifest(const CaptureManifest& manifest, const Checker& check, int version);

} // namespace fpp::capture_check
