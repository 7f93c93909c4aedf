#pragma once
// Capture sets, format fpp-capture/1 (spec/capture-set.md): a folder with
// capture.yaml and one PNG per frame. The reader is strict: every rejection the
// spec lists throws InputError naming the file and the field.

#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace fpp {

inline constexpr const char* kCaptureFormat = "fpp-capture/1";
inline constexpr const char* kBoardFormat = "fpp-board/1";

// Optional ground truth of simulated sets (paths relative to the folder).
struct TruthFiles {
    std::string xyz;       // 3-channel float32 TIFF, camera frame, mm, NaN = no surface
    std::string projector; // 2-channel float32 TIFF, projector (x, y) per camera pixel
};

struct CaptureManifest {
    Size camera;
    Size projector;
    std::vector<std::string> frames; // capture order, relative to the folder
    Sequence sequence;
    std::string metadata_yaml; // the free-form `metadata` map, kept as YAML text
    std::optional<TruthFiles> truth;
};

struct CaptureSet {
    std::filesystem::path folder;
    CaptureManifest manifest;
    std::vector<Frame> frames; // same order as manifest.frames
};

// Parses and validates capture.yaml (`path` is the yaml file). Does not open frames.
CaptureManifest read_manifest(const std::filesystem::path& path);
// Reads a capture folder: manifest plus every frame, checked for existence,
// size and uniform bit depth.
CaptureSet read_capture_set(const std::filesystem::path& folder);
// Serialises a manifest exactly as the spec lays it out.
std::string manifest_to_yaml(const CaptureManifest& manifest);
// Writes a whole capture set atomically: frames and manifest go to a temporary
// sibling folder which is renamed onto `folder` only when complete. `folder`
// must not exist yet. Frames are written as 8- or 16-bit PNG per their depth.
void write_capture_set(const std::filesystem::path& folder, const CaptureManifest& manifest,
                       const std::vector<Frame>& frames);

// Reads a pattern sequence alone from a YAML file holding a `sequence:` list in
// the manifest's syntax (used for named scan sequences and board configs).
Sequence read_sequence(const std::filesystem::path& path);
// Same, from YAML text (`origin` names the source in errors).
Sequence parse_sequence(const std::string& yaml_text, const std::filesystem::path& origin);

// board.yaml of a calibration session.
struct BoardDescription {
    enum class Kind { checkerboard, plane } kind = Kind::checkerboard;
    int inner_columns = 0; // checkerboard only
    int inner_rows = 0;
    double square_size = 0; // mm
};
BoardDescription read_board(const std::filesystem::path& path);

} // namespace fpp
