#pragma once
// Capture sets, formats fpp-capture/1 and fpp-capture/2
// (firmware/core/formats/capture-set.md): a folder with capture.yaml and one
// frame file (PNG, TIFF or BMP, 8- or 16-bit grey) per frame. The reader is
// strict: every rejection the spec lists throws InputError naming the file
// and the field.
//
// Field names in errors are YAML paths: "camera.width", "frames[3]",
// "sequence[2].period", "truth.xyz". Problems with the manifest name
// capture.yaml; problems with one frame file (missing, wrong size, wrong bit
// depth, not a grey image, values above bit_depth) name that frame file and
// the field "frames[i]".
//
// Beyond the spec's list the reader also rejects: periods that are not > 0,
// steps < 3, shift_sign other than +1/-1, bits outside 1..30, levels^bits
// above 2^30, a gray block whose bits cannot number every code step the
// projector touches, a code-only gray block (v2) without a threshold
// reference, centerline width <= 0 or a line that lights no projector pixel,
// camera/projector sizes outside 1..65535, unknown keys anywhere except
// inside `metadata`, v2 keys in a v1 file, duplicate keys, quoted numbers,
// non-decimal or fractional integers, booleans other than true/false,
// absolute frame paths or paths with "..", duplicate frame names, an empty
// sequence, and truth files listed but missing.

#include "fpp/enum_names.hpp"
#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace fpp {

inline constexpr const char* kCaptureFormat = "fpp-capture/1";
inline constexpr const char* kCaptureFormatV2 = "fpp-capture/2";
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
    // v2 `bit_depth`: bits in use of 16-bit frames, LSB-aligned (9..16); 0 =
    // not declared (the reader finds it from the frames' largest value and
    // sets Frame::significant_bits either way).
    int bit_depth = 0;
    friend bool operator==(const CaptureManifest&, const CaptureManifest&) = default;
};

// Where a set's bits in use come from.
enum class BitsInUseSource {
    container, // 8-bit frames, no bit_depth: 8
    declared,  // `bit_depth` in capture.yaml (checked against every frame)
    found,     // 16-bit frames, no bit_depth: from the largest value of the frames read
};
inline constexpr EnumName<BitsInUseSource> kBitsInUseSourceNames[] = {
    {BitsInUseSource::container, "container"},
    {BitsInUseSource::declared, "declared"},
    {BitsInUseSource::found, "found"},
};
const char* to_string(BitsInUseSource source); // "container", "declared", "found"

struct CaptureSet {
    std::filesystem::path folder;
    CaptureManifest manifest;
    std::vector<Frame> frames; // same order as manifest.frames
    // Bits in use of every frame (also in each Frame::significant_bits): the
    // declared bit_depth, or for 16-bit frames without one the smallest of
    // 9 (largest value <= 511), 10, 12, 14, 16 that holds the largest value
    // over the frames read; 8 for 8-bit frames.
    int bits_in_use = 0;
    BitsInUseSource bits_source = BitsInUseSource::container;
};

// Parses and validates capture.yaml (`path` is the yaml file). Does not open frames.
CaptureManifest read_manifest(const std::filesystem::path& path);
// Same, from YAML text; `origin` is the file named in errors.
CaptureManifest parse_manifest(const std::string& yaml_text, const std::filesystem::path& origin);
// Reads a capture folder: manifest plus every frame (read_frame: PNG, TIFF or
// BMP), checked for existence, size, uniform bit depth and values within the
// declared bit_depth; sets the bits in use; truth files, when listed, must exist.
CaptureSet read_capture_set(const std::filesystem::path& folder);
// Same, reading only the frames of the blocks `keep` accepts (for a reader
// that needs, say, the projector's x alone): the set's manifest lists just
// those blocks and their frames, and only those frames are checked and read.
CaptureSet read_capture_set(const std::filesystem::path& folder,
                            const std::function<bool(const PatternBlock&)>& keep);
// Serialises a manifest exactly as the spec lays it out: format, camera,
// projector, bit_depth (when non-zero), frames, sequence (every field
// written, defaults included), truth if any, metadata. The format is
// fpp-capture/1 when the manifest uses nothing of version 2, else
// fpp-capture/2 (whose blocks then list every v2 field too). Numbers are written so that they read
// back bit-exactly. Throws InputError (origin "capture.yaml") if the manifest is invalid.
std::string manifest_to_yaml(const CaptureManifest& manifest);

// Throws InputError(origin, field, ...) for anything the reader would reject
// in a manifest (everything except the frame files themselves).
void validate_manifest(const CaptureManifest& manifest, const std::filesystem::path& origin);

// Ground-truth images written along with a simulated capture set.
struct TruthImages {
    const Image<float>* xyz = nullptr; // 3 channels, camera size; to manifest.truth->xyz
    const Image<float>* projector =
        nullptr; // 2 channels, camera size; to manifest.truth->projector
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

// A capture set held in memory (frames from a program rather than files):
// the manifest checked as write_capture_set checks it, the frames against it
// as write_capture_set checks them (InputError naming folder / the frame's
// listed name and "frames[i]"), the bits in use set as read_capture_set sets
// them. `folder` only names the set in errors; nothing is read or written.
CaptureSet make_capture_set(const std::filesystem::path& folder, CaptureManifest manifest,
                            std::vector<Frame> frames);

// A capture set whose frames are borrowed, not owned (FrameView: samples the
// caller keeps alive and unchanged while the view is used), for a program
// that holds its frames elsewhere (fpp.decode on NumPy arrays). Decoded,
// judged and diagnosed exactly as the CaptureSet holding the same samples.
struct CaptureView {
    std::filesystem::path folder;
    CaptureManifest manifest;
    std::vector<FrameView> frames; // same order as manifest.frames
    int bits_in_use = 0;           // as CaptureSet's (also in each view's significant_bits)
    BitsInUseSource bits_source = BitsInUseSource::container;
};

// A view of `set` (its manifest copied, its frames borrowed).
CaptureView view_of(const CaptureSet& set);

// make_capture_set's checks and bits in use on borrowed frames: the same
// refusals and messages; no sample is copied.
CaptureView make_capture_view(const std::filesystem::path& folder, CaptureManifest manifest,
                              std::vector<FrameView> frames);

// Reads a pattern sequence alone from a YAML file holding a `sequence:` list in
// the manifest's syntax (used for named scan sequences and board configs).
// Other top-level keys of that file are ignored. Every fpp-capture/2 block
// form is accepted except `fringes` (it needs the projector size). Without a
// projector size the checks that need one (code coverage, centerline inside
// the projector, micro periods below the extent) are left to validate_sequence.
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
