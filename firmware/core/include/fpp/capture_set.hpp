#pragma once
// Capture sets, format fpp-capture/1 (firmware/core/formats/capture-set.md): a folder with
// capture.yaml and one PNG per frame. The reader is strict: every rejection the
// spec lists throws InputError naming the file and the field.
//
// Field names in errors are YAML paths: "camera.width", "frames[3]",
// "sequence[2].period", "truth.xyz". Problems with the manifest name
// capture.yaml; problems with one frame file (missing, wrong size, wrong bit
// depth, not a grey PNG) name that frame file and the field "frames[i]".
//
// Beyond the spec's list the reader also rejects: periods that are not > 0,
// steps < 3, shift_sign other than +1/-1, bits outside 1..30, a gray block
// whose period matches no phase block on its axis (it indexes that block's
// periods) or whose bits cannot number every period across the projector
// (floor((extent - 1) / period) >= 2^bits), centerline width <= 0 or a line
// that lights no projector pixel, camera/projector sizes outside 1..65535,
// unknown keys anywhere except inside `metadata`, duplicate keys, quoted
// numbers, non-decimal or fractional integers, booleans other than
// true/false, absolute frame paths or paths with "..", duplicate frame
// names, an empty sequence, and truth files listed but missing.

#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace fpp {

inline constexpr const char* kCaptureFormat = "fpp-capture/1";
inline constexpr const char* kBoardFormat = "fpp-board/1";

// Optional ground truth of simulated sets (paths relative to the folder).
// Either may be empty (not provided), not both.
struct TruthFiles {
    std::string xyz;       // 3-channel float32 TIFF, camera frame, mm, NaN = no surface
    std::string projector; // 2-channel float32 TIFF, projector (x, y) per camera pixel
    friend bool operator==(const TruthFiles&, const TruthFiles&) = default;
};

struct CaptureManifest {
    Size camera;
    Size projector;
    std::vector<std::string> frames; // capture order, relative to the folder
    Sequence sequence;
    // The free-form `metadata` map, kept as YAML text in the form the reader
    // produces (yaml-cpp's dump of the map, no trailing newline; "" when absent
    // or empty). The writer accepts any YAML map text here.
    std::string metadata_yaml;
    std::optional<TruthFiles> truth;
    friend bool operator==(const CaptureManifest&, const CaptureManifest&) = default;
};

struct CaptureSet {
    std::filesystem::path folder;
    CaptureManifest manifest;
    std::vector<Frame> frames; // same order as manifest.frames
};

// Parses and validates capture.yaml (`path` is the yaml file). Does not open frames.
CaptureManifest read_manifest(const std::filesystem::path& path);
// Same, from YAML text; `origin` is the file named in errors.
CaptureManifest parse_manifest(const std::string& yaml_text, const std::filesystem::path& origin);
// Reads a capture folder: manifest plus every frame, checked for existence,
// size and uniform bit depth; truth files, when listed, must exist.
CaptureSet read_capture_set(const std::filesystem::path& folder);
// Same, reading only the frames of the blocks `keep` accepts (for a reader
// that needs, say, the projector's x alone): the set's manifest lists just
// those blocks and their frames, and only those frames are checked and read.
CaptureSet read_capture_set(const std::filesystem::path& folder,
                            const std::function<bool(const PatternBlock&)>& keep);
// Serialises a manifest exactly as the spec lays it out: format, camera,
// projector, frames, sequence (every field written, defaults included), truth
// if any, metadata. Numbers are written so that they read back bit-exactly.
// Throws InputError (origin "capture.yaml") if the manifest is invalid.
std::string manifest_to_yaml(const CaptureManifest& manifest);

// Throws InputError(origin, field, ...) for anything the reader would reject
// in a manifest (everything except the frame files themselves).
void validate_manifest(const CaptureManifest& manifest, const std::filesystem::path& origin);

// Ground-truth images written along with a simulated capture set.
struct TruthImages {
    const Image<float>* xyz = nullptr;       // 3 channels, camera size; to manifest.truth->xyz
    const Image<float>* projector = nullptr; // 2 channels, camera size; to manifest.truth->projector
};

// Writes a whole capture set atomically: frames and manifest go to a temporary
// sibling folder which is renamed onto `folder` only when complete. `folder`
// must not exist yet (IoError). Frames are written as 8- or 16-bit PNG per
// their depth. An invalid manifest, or frames that do not match it, throw
// InputError naming `folder`/capture.yaml and the field; nothing is left behind
// by a failure.
void write_capture_set(const std::filesystem::path& folder, const CaptureManifest& manifest,
                       const std::vector<Frame>& frames);
// Same, also writing the truth TIFFs that manifest.truth lists (both must be
// given exactly when listed).
void write_capture_set(const std::filesystem::path& folder, const CaptureManifest& manifest,
                       const std::vector<Frame>& frames, const TruthImages& truth);

// Reads a pattern sequence alone from a YAML file holding a `sequence:` list in
// the manifest's syntax (used for named scan sequences and board configs).
// Other top-level keys of that file are ignored. Without a projector size the
// checks that need one (Gray coverage, centerline inside the projector) are
// left to validate_sequence.
Sequence read_sequence(const std::filesystem::path& path);
// Same, from YAML text (`origin` names the source in errors).
Sequence parse_sequence(const std::string& yaml_text, const std::filesystem::path& origin);
// Every check the manifest reader makes on a sequence for this projector.
// Field names are "sequence[i].<key>".
void validate_sequence(const Sequence& sequence, Size projector,
                       const std::filesystem::path& origin);

// board.yaml of a calibration session.
struct BoardDescription {
    enum class Kind { checkerboard, plane } kind = Kind::checkerboard;
    int inner_columns = 0; // checkerboard only
    int inner_rows = 0;
    double square_size = 0; // mm; optional (0 if absent) for a plane
    friend bool operator==(const BoardDescription&, const BoardDescription&) = default;
};
BoardDescription read_board(const std::filesystem::path& path);
BoardDescription parse_board(const std::string& yaml_text, const std::filesystem::path& origin);

} // namespace fpp
