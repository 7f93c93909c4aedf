#include "fpp/capture_set.hpp"

#include "capture_manifest_check.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"
#include "fpp/image_io.hpp"
#include "fpp/parallel.hpp"
#include "fpp/yaml_fields.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <exception>
#include <functional>
#include <map>
#include <set>

namespace fpp {

namespace {

// "" for a regular file, else why not: "not found", or the file system's
// reason for a name it cannot look up (too long, a loop of links, ...),
// which must not escape as std::filesystem::filesystem_error.
std::string not_a_regular_file(const std::filesystem::path& path) {
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (std::filesystem::is_regular_file(status))
        return {};
    if (ec && ec != std::errc::no_such_file_or_directory)
        return "cannot be looked up: " + ec.message();
    return std::filesystem::exists(status) ? "is not a regular file" : "not found";
}

namespace fs = std::filesystem;
using yaml_fields::child;
using yaml_fields::item;

using capture_check::Checker;
using capture_check::kManifestName;

// Runs f(0..n-1) on up to four threads (the work is file decoding and
// fsync, not arithmetic); rethrows the exception of the lowest failing index.
void for_each_file(std::size_t n, const std::function<void(std::size_t)>& f) {
    if (n == 0)
        return;
    const int count = static_cast<int>(n);
    ThreadPool pool(std::min({ThreadPool::resolve_threads(0), 4, count}));
    std::vector<std::exception_ptr> errors(n);
    std::atomic<bool> failed{false};
    pool.parallel_for(count, 1, [&](int begin, int end, int) {
        for (int k = begin; k < end && !failed; ++k) {
            const auto i = static_cast<std::size_t>(k);
            try {
                f(i);
            } catch (...) {
                errors[i] = std::current_exception();
                failed = true;
            }
        }
    });
    for (const auto& e : errors) {
        if (e)
            std::rethrow_exception(e);
    }
}

// Message of an InputError without its "file: field: " prefix, to re-raise
// it with the frame's field.
std::string bare_message(const InputError& e) {
    std::string what = e.what();
    std::string prefix = e.file().string() + ": ";
    if (!e.field().empty())
        prefix += e.field() + ": ";
    return what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what;
}

// bit_depth against the frames' container depth.
void check_declared_depth(const CaptureManifest& m, int container_bits, const fs::path& origin) {
    if (m.bit_depth == 0)
        return;
    if (container_bits == 8 && m.bit_depth != 8) {
        throw InputError(origin, "bit_depth",
                         "bit_depth " + std::to_string(m.bit_depth) +
                             " needs 16-bit frames, but the frames are 8-bit (give 8 or "
                             "leave bit_depth out)");
    }
    if (container_bits == 16 && m.bit_depth < 9) {
        throw InputError(origin, "bit_depth",
                         "bit_depth " + std::to_string(m.bit_depth) +
                             " with 16-bit frames: give 9 to 16, the bits the camera uses");
    }
}

int largest_value(const FrameView& frame) {
    int largest = 0;
    const std::size_t n = frame.empty() ? 0 : frame.sample_count();
    if (frame.bit_depth == 8) {
        const std::uint8_t* v = frame.u8();
        for (std::size_t i = 0; i < n; ++i)
            largest = std::max(largest, int{v[i]});
    } else {
        const std::uint16_t* v = frame.u16();
        for (std::size_t i = 0; i < n; ++i)
            largest = std::max(largest, int{v[i]});
    }
    return largest;
}

// Declared bit_depth (checked against every frame's largest value), or found
// from the largest value over the frames: 9 (<= 511), 10, 12, 14 or 16 bits.
// (A CaptureSet or a CaptureView.)
template <class Set>
void set_bits_in_use(Set& set, const std::vector<int>& largest,
                     const std::vector<std::size_t>& listed) {
    if (set.frames.empty())
        return;
    const CaptureManifest& m = set.manifest;
    const int container = set.frames[0].bit_depth;
    int bits = container;
    set.bits_source = BitsInUseSource::container;
    if (m.bit_depth != 0) {
        bits = m.bit_depth;
        set.bits_source = BitsInUseSource::declared;
        const int full_scale = (1 << bits) - 1;
        for (std::size_t i = 0; i < largest.size(); ++i) {
            if (largest[i] > full_scale) {
                throw InputError(set.folder / m.frames[i], item("frames", listed[i]),
                                 "holds the value " + std::to_string(largest[i]) +
                                     ", above the largest of bit_depth " + std::to_string(bits) +
                                     " (" + std::to_string(full_scale) + ") declared in " +
                                     (set.folder / kManifestName).string());
            }
        }
    } else if (container == 16) {
        const int overall = *std::max_element(largest.begin(), largest.end());
        bits = 16;
        for (const int candidate : {9, 10, 12, 14}) {
            if (overall <= (1 << candidate) - 1) {
                bits = candidate;
                break;
            }
        }
        set.bits_source = BitsInUseSource::found;
    }
    set.bits_in_use = bits;
    for (auto& f : set.frames)
        f.significant_bits = bits;
}

} // namespace

// ---------------------------------------------------------------------------

const char* to_string(BitsInUseSource source) {
    return name_of(kBitsInUseSourceNames, source, "container");
}

void validate_manifest(const CaptureManifest& manifest, const std::filesystem::path& origin) {
    capture_check::check_manifest(manifest, Checker(origin, nullptr), 2);
}

void validate_sequence(const Sequence& sequence, Size projector,
                       const std::filesystem::path& origin) {
    const Checker check(origin, nullptr);
    capture_check::check_size(projector, "projector", check);
    capture_check::check_sequence_on_projector(sequence, projector, check, 2);
}

CaptureSet read_capture_set(const std::filesystem::path& folder) {
    return read_capture_set(folder, [](const PatternBlock&) { return true; });
}

CaptureSet read_capture_set(const std::filesystem::path& folder,
                            const std::function<bool(const PatternBlock&)>& keep) {
    CaptureSet set;
    set.folder = folder;
    set.manifest = read_manifest(folder / kManifestName);
    // The kept blocks and their frames; listed[i]: where frame i is listed
    // in capture.yaml (errors name that field).
    std::vector<std::size_t> listed;
    {
        CaptureManifest& all = set.manifest;
        Sequence sequence;
        std::vector<std::string> frames;
        std::size_t first = 0;
        for (const PatternBlock& block : all.sequence) {
            const std::size_t count = static_cast<std::size_t>(frame_count(block));
            if (keep(block)) {
                sequence.push_back(block);
                for (std::size_t k = first; k < first + count && k < all.frames.size(); ++k) {
                    frames.push_back(all.frames[k]);
                    listed.push_back(k);
                }
            }
            first += count;
        }
        all.sequence = std::move(sequence);
        all.frames = std::move(frames);
    }
    const CaptureManifest& m = set.manifest;
    const std::size_t n = m.frames.size();

    // Cheap checks on every file first so that a bad set fails before decoding.
    std::vector<FrameInfo> infos(n);
    for (std::size_t i = 0; i < n; ++i) {
        const fs::path path = folder / m.frames[i];
        const std::string field = item("frames", listed[i]);
        if (const std::string why = not_a_regular_file(path); !why.empty()) {
            throw InputError(path, field,
                             "frame file " + why + " (listed in " +
                                 (folder / kManifestName).string() + ")");
        }
        try {
            infos[i] = read_frame_info(path);
        } catch (const InputError& e) {
            throw InputError(path, field, bare_message(e));
        }
        const FrameInfo& info = infos[i];
        if (info.size != m.camera) {
            throw InputError(path, field,
                             "frame is " + std::to_string(info.size.width) + "x" +
                                 std::to_string(info.size.height) + " pixels but camera is " +
                                 std::to_string(m.camera.width) + "x" +
                                 std::to_string(m.camera.height) + " in capture.yaml");
        }
        if (info.bit_depth != infos[0].bit_depth) {
            throw InputError(path, field,
                             "frame is " + std::to_string(info.bit_depth) + "-bit but " +
                                 item("frames", listed[0]) + " is " +
                                 std::to_string(infos[0].bit_depth) +
                                 "-bit (all frames of a set share one bit depth)");
        }
    }
    if (n > 0)
        check_declared_depth(m, infos[0].bit_depth, folder / kManifestName);
    if (m.truth) {
        for (const auto& [name, key] :
             {std::pair{m.truth->xyz, "xyz"}, std::pair{m.truth->projector, "projector"}}) {
            if (name.empty())
                continue;
            const fs::path path = folder / name;
            if (const std::string why = not_a_regular_file(path); !why.empty()) {
                throw InputError(path, child("truth", key),
                                 "truth file " + why + " (listed in " +
                                     (folder / kManifestName).string() + ")");
            }
        }
    }

    set.frames.resize(n);
    std::vector<int> largest(n, 0);
    for_each_file(n, [&](std::size_t i) {
        const fs::path path = folder / m.frames[i];
        try {
            set.frames[i] = read_frame(path);
        } catch (const InputError& e) {
            throw InputError(path, item("frames", listed[i]), bare_message(e));
        }
        // The file may have changed since its header was read.
        if (set.frames[i].size() != m.camera || set.frames[i].bit_depth != infos[0].bit_depth) {
            throw InputError(path, item("frames", listed[i]),
                             "frame changed while the set was read");
        }
        largest[i] = largest_value(set.frames[i]);
    });
    set_bits_in_use(set, largest, listed);
    return set;
}

namespace {

// The frames given for `m` (write_capture_set, make_capture_set): as many as
// it lists, 8- or 16-bit grey, the camera's size, one bit depth, within the
// declared bit_depth. InputError naming folder / the frame and "frames[i]".
void check_frames(const fs::path& folder, const CaptureManifest& m,
                  const std::vector<FrameView>& frames, const Checker& check) {
    const fs::path origin = folder / kManifestName;
    if (frames.size() != m.frames.size()) {
        check.fail("frames", std::to_string(frames.size()) + " frame images given for " +
                                 std::to_string(m.frames.size()) + " listed frames");
    }
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const FrameView& f = frames[i];
        const fs::path path = folder / m.frames[i];
        const std::string field = item("frames", i);
        if (f.bit_depth != 8 && f.bit_depth != 16) {
            throw InputError(path, field,
                             "bit depth " + std::to_string(f.bit_depth) +
                                 " (frames are 8- or 16-bit)");
        }
        if (f.channels != 1) {
            throw InputError(path, field,
                             std::to_string(f.channels) + " channels (frames are grey)");
        }
        if (f.size != m.camera) {
            throw InputError(path, field,
                             "frame is " + std::to_string(f.size.width) + "x" +
                                 std::to_string(f.size.height) + " pixels but camera is " +
                                 std::to_string(m.camera.width) + "x" +
                                 std::to_string(m.camera.height));
        }
        if (f.bit_depth != frames[0].bit_depth) {
            throw InputError(path, field,
                             "frame is " + std::to_string(f.bit_depth) + "-bit but frames[0] is " +
                                 std::to_string(frames[0].bit_depth) + "-bit");
        }
    }
    if (!frames.empty()) {
        check_declared_depth(m, frames[0].bit_depth, origin);
        if (m.bit_depth != 0) {
            for (std::size_t i = 0; i < frames.size(); ++i) {
                if (largest_value(frames[i]) > (1 << m.bit_depth) - 1) {
                    throw InputError(folder / m.frames[i], item("frames", i),
                                     "holds values above the largest of bit_depth " +
                                         std::to_string(m.bit_depth));
                }
            }
        }
    }
}

std::vector<FrameView> views_of(const std::vector<Frame>& frames) {
    return {frames.begin(), frames.end()};
}

} // namespace

CaptureView view_of(const CaptureSet& set) {
    return {set.folder, set.manifest, views_of(set.frames), set.bits_in_use, set.bits_source};
}

CaptureView make_capture_view(const std::filesystem::path& folder, CaptureManifest manifest,
                              std::vector<FrameView> frames) {
    const Checker check(folder / kManifestName, nullptr);
    capture_check::check_manifest(manifest, check, 2);
    check_frames(folder, manifest, frames, check);
    CaptureView view;
    view.folder = folder;
    view.manifest = std::move(manifest);
    view.frames = std::move(frames);
    // The largest values matter to a declared depth and to 16-bit frames
    // only (8-bit frames use their container's): no pass over 8-bit samples.
    const bool needed =
        view.manifest.bit_depth != 0 || (!view.frames.empty() && view.frames[0].bit_depth == 16);
    std::vector<int> largest(view.frames.size());
    std::vector<std::size_t> listed(view.frames.size());
    for (std::size_t i = 0; i < view.frames.size(); ++i) {
        largest[i] = needed ? largest_value(view.frames[i]) : 0;
        listed[i] = i;
    }
    set_bits_in_use(view, largest, listed);
    return view;
}

CaptureSet make_capture_set(const std::filesystem::path& folder, CaptureManifest manifest,
                            std::vector<Frame> frames) {
    const fs::path origin = folder / kManifestName;
    const Checker check(origin, nullptr);
    capture_check::check_manifest(manifest, check, 2);
    check_frames(folder, manifest, views_of(frames), check);
    CaptureSet set;
    set.folder = folder;
    set.manifest = std::move(manifest);
    set.frames = std::move(frames);
    std::vector<int> largest(set.frames.size());
    std::vector<std::size_t> listed(set.frames.size());
    for (std::size_t i = 0; i < set.frames.size(); ++i) {
        largest[i] = largest_value(set.frames[i]);
        listed[i] = i;
    }
    set_bits_in_use(set, largest, listed);
    return set;
}

void write_capture_set(const std::filesystem::path& folder, const CaptureManifest& manifest,
                       const std::vector<Frame>& frames) {
    write_capture_set(folder, manifest, frames, TruthImages{});
}

void write_capture_set(const std::filesystem::path& folder, const CaptureManifest& manifest,
                       const std::vector<Frame>& frames, const TruthImages& truth) {
    const fs::path origin = folder / kManifestName;
    const Checker check(origin, nullptr);
    capture_check::check_manifest(manifest, check, 2);
    const CaptureManifest& m = manifest;

    check_frames(folder, m, views_of(frames), check);
    struct TruthEntry {
        std::string name;
        const Image<float>* image;
        const char* field;
        int channels;
    };
    const std::vector<TruthEntry> truth_entries = {
        {m.truth ? m.truth->xyz : "", truth.xyz, "truth.xyz", 3},
        {m.truth ? m.truth->projector : "", truth.projector, "truth.projector", 2}};
    for (const auto& t : truth_entries) {
        if (t.name.empty() != (t.image == nullptr)) {
            check.fail(t.field, t.name.empty() ? "an image is given but the manifest lists no file"
                                               : "listed in the manifest but no image is given");
        }
        if (!t.image)
            continue;
        if (t.image->size() != m.camera || t.image->channels() != t.channels) {
            check.fail(t.field, "image must be " + std::to_string(t.channels) + "-channel at " +
                                    "camera size " + std::to_string(m.camera.width) + "x" +
                                    std::to_string(m.camera.height));
        }
    }
    const std::string yaml = manifest_to_yaml(m);

    write_folder_atomically(folder, [&](const fs::path& temp) {
        // Subfolders named by frame paths, fsynced once everything is in them.
        std::set<fs::path> subfolders;
        auto prepare = [&](const std::string& name) {
            const fs::path parent = fs::path(name).parent_path();
            if (parent.empty())
                return;
            fs::create_directories(temp / parent);
            for (fs::path p = parent; !p.empty(); p = p.parent_path())
                subfolders.insert(temp / p);
        };
        for (const auto& name : m.frames)
            prepare(name);
        for (const auto& t : truth_entries) {
            if (t.image)
                prepare(t.name);
        }
        for_each_file(frames.size(),
                      [&](std::size_t i) { write_png_synced(temp / m.frames[i], frames[i]); });
        for (const auto& t : truth_entries) {
            if (t.image)
                write_tiff_synced(temp / t.name, *t.image);
        }
        write_file_synced(temp / kManifestName, yaml);
        for (auto it = subfolders.rbegin(); it != subfolders.rend(); ++it)
            fsync_path(*it);
    });
}

} // namespace fpp
