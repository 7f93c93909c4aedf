// fpp-calib import: a folder of another tool's frames becomes a capture set.
// The frames are copied as they are; capture.yaml describes them
// (capture_import.hpp).

#include "fpp/calib/capture_import.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <optional>

namespace fpp::calib {

namespace fs = std::filesystem;

namespace {

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

bool is_image(const fs::path& p) {
    const std::string ext = lower(p.extension().string());
    return ext == ".png" || ext == ".tif" || ext == ".tiff" || ext == ".bmp";
}

// The last run of digits in the file's stem.
std::optional<long long> last_number(const fs::path& p) {
    const std::string stem = p.stem().string();
    std::size_t end = stem.size();
    while (end > 0 && std::isdigit(static_cast<unsigned char>(stem[end - 1])) == 0)
        --end;
    std::size_t begin = end;
    while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1])) != 0)
        --begin;
    if (begin == end || end - begin > 15)
        return std::nullopt;
    return std::stoll(stem.substr(begin, end - begin));
}

std::string sequence_text(const Sequence& s) {
    std::string t;
    for (const auto& b : s)
        t +=
            (t.empty() ? "" : ", ") + pattern_name(b) + " (" + std::to_string(frame_count(b)) + ")";
    return t;
}

struct FrameFacts {
    Size size;
    int depth = 8;
};

FrameFacts inspect_frame(const fs::path& path, const std::string& field) {
    cv::Mat image;
    try {
        image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception& e) {
        throw InputError(path, field, "cannot be read as an image: " + e.msg);
    }
    if (image.empty())
        throw InputError(path, field, "cannot be read as an image (PNG, TIFF or BMP)");
    if (image.channels() != 1)
        throw InputError(path, field,
                         "a " + std::to_string(image.channels()) +
                             "-channel image: capture sets hold grey frames (save the "
                             "camera's frames as 8- or 16-bit grey)");
    if (image.depth() != CV_8U && image.depth() != CV_16U)
        throw InputError(path, field, "expected 8- or 16-bit unsigned pixels");
    return {{image.cols, image.rows}, image.depth() == CV_8U ? 8 : 16};
}

void copy_synced(const fs::path& from, const fs::path& to) {
    std::ifstream in(from, std::ios::binary | std::ios::ate);
    if (!in)
        throw IoError(from, "cannot open for reading");
    std::string bytes(static_cast<std::size_t>(in.tellg()), '\0');
    in.seekg(0);
    if (!in.read(bytes.data(), static_cast<std::streamsize>(bytes.size())))
        throw IoError(from, "cannot read");
    write_file_synced(to, bytes);
}

} // namespace

std::vector<fs::path> list_frame_files(const fs::path& folder) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec))
        throw InputError(folder, "", "not a folder of frames");
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(folder))
        if (entry.is_regular_file() && is_image(entry.path()))
            files.push_back(entry.path());
    const bool numbered = std::all_of(files.begin(), files.end(),
                                      [](const fs::path& p) { return last_number(p).has_value(); });
    std::sort(files.begin(), files.end(), [numbered](const fs::path& a, const fs::path& b) {
        if (numbered && *last_number(a) != *last_number(b))
            return *last_number(a) < *last_number(b);
        return a.filename() < b.filename();
    });
    return files;
}

CaptureManifest import_capture(const fs::path& frames, const fs::path& out,
                               const ImportOptions& options) {
    const Sequence sequence = import_sequence(options, frames);
    const std::vector<fs::path> files = list_frame_files(frames);
    const int needed = frame_count(sequence);
    if (static_cast<int>(files.size()) != needed)
        throw InputError(frames, "frames",
                         "found " + std::to_string(files.size()) +
                             " image files (PNG, TIFF, BMP), but " + to_string(options.tool) +
                             "'s " + options.codec + " (direction " + options.direction + ") has " +
                             std::to_string(needed) + " frames: " + sequence_text(sequence));

    CaptureManifest m;
    m.projector = options.projector;
    m.sequence = sequence;
    const std::vector<int> order = import_frame_order(options, sequence);
    FrameFacts first{};
    for (std::size_t i = 0; i < files.size(); ++i) {
        const std::string field = "frames[" + std::to_string(i) + "]";
        const FrameFacts f = inspect_frame(files[i], field);
        if (i == 0)
            first = f;
        else if (!(f.size == first.size) || f.depth != first.depth)
            throw InputError(
                files[i], field,
                "frame is " + std::to_string(f.size.width) + "x" + std::to_string(f.size.height) +
                    " " + std::to_string(f.depth) + "-bit but " + files[0].filename().string() +
                    " is " + std::to_string(first.size.width) + "x" +
                    std::to_string(first.size.height) + " " + std::to_string(first.depth) + "-bit");
    }
    for (int index : order)
        m.frames.push_back(files[std::size_t(index)].filename().string());
    m.camera = first.size;
    if (options.bit_depth != 0) {
        if (first.depth != 16 || options.bit_depth < 9 || options.bit_depth > 16)
            throw InputError(frames, "bit_depth",
                             "declared for 16-bit frames only, 9..16 (the frames are " +
                                 std::to_string(first.depth) + "-bit)");
        m.bit_depth = options.bit_depth;
    }
    m.metadata_yaml = "{imported_from: " + std::string(to_string(options.tool)) + ", codec: \"" +
                      options.codec + "\", direction: " + options.direction + "}";
    const std::string yaml = manifest_to_yaml(m); // validates
    write_folder_atomically(out, [&](const fs::path& temp) {
        for (const auto& file : files)
            copy_synced(file, temp / file.filename());
        write_file_synced(temp / "capture.yaml", yaml);
    });
    return m;
}

} // namespace fpp::calib
