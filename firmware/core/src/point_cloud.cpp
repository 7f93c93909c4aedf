#include "fpp/point_cloud.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"
#include "fpp/yaml_fields.hpp"

#include <array>
#include <bit>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <limits>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <type_traits>

namespace fpp {

namespace {

// x y z quality intensity [sigma_z] (float), pixel (uint).
std::size_t record_bytes(const PointCloud& cloud) {
    return cloud.sigma_z.empty() ? 6 * 4 : 7 * 4;
}

bool has_point(const float* p) {
    return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

// Byte order reversal (std::byteswap is C++23).
template <class U> U swap_bytes(U v) {
    U r = 0;
    for (std::size_t i = 0; i < sizeof(U); ++i) {
        r = static_cast<U>((r << 8) | (v & 0xFF));
        v = static_cast<U>(v >> 8);
    }
    return r;
}

// Little-endian bytes of a 32-bit value (PLY binary_little_endian).
void put_u32(char* out, std::uint32_t v) {
    if constexpr (std::endian::native == std::endian::big)
        v = swap_bytes(v);
    std::memcpy(out, &v, 4);
}
void put_f32(char* out, float f) {
    put_u32(out, std::bit_cast<std::uint32_t>(f));
}

std::string one_line(const std::string& s) {
    std::string r = s;
    for (char& c : r)
        if (c == '\n' || c == '\r')
            c = ' ';
    return r;
}

void check_cloud(const PointCloud& cloud) {
    if (cloud.xyz.channels() != 3 && !cloud.xyz.empty())
        throw std::invalid_argument("point cloud: xyz must have 3 channels");
    for (const Image<float>* extra : {&cloud.quality, &cloud.intensity, &cloud.sigma_z})
        if (!extra->empty() && (extra->channels() != 1 || extra->size() != cloud.xyz.size()))
            throw std::invalid_argument(
                "point cloud: quality, intensity and sigma_z must be empty or 1-channel images "
                "of the cloud's size");
    if (cloud.xyz.pixel_count() > std::size_t{std::numeric_limits<std::uint32_t>::max()})
        throw std::invalid_argument("point cloud: more pixels than a 32-bit index can number");
}

} // namespace

std::size_t PointCloud::count_points() const {
    if (xyz.channels() != 3)
        return 0;
    std::size_t n = 0;
    const float* p = xyz.data();
    for (std::size_t i = 0, count = xyz.pixel_count(); i < count; ++i, p += 3)
        n += has_point(p) ? 1 : 0;
    return n;
}

namespace {

std::string ply_header(const PointCloud& cloud, const std::vector<std::string>& comments,
                       std::size_t points) {
    std::ostringstream header;
    header << "ply\nformat binary_little_endian 1.0\n";
    for (const auto& c : comments)
        header << "comment " << one_line(c) << "\n";
    header << "obj_info organised_width " << cloud.xyz.width() << "\n"
           << "obj_info organised_height " << cloud.xyz.height() << "\n"
           << "element vertex " << points << "\n"
           << "property float x\nproperty float y\nproperty float z\n"
           << "property float quality\nproperty float intensity\n"
           << (cloud.sigma_z.empty() ? "" : "property float sigma_z\n")
           << "property uint pixel\nend_header\n";
    return header.str();
}

// Encodes the records of the slots with a point from slot `pixel` on, at most
// `max_points` of them, into `out`; advances `pixel` past the last slot read
// and returns the number of records.
std::size_t encode_records(const PointCloud& cloud, std::size_t& pixel, char* out,
                           std::size_t max_points) {
    constexpr float nan = std::numeric_limits<float>::quiet_NaN();
    const float* xyz = cloud.xyz.data();
    const float* quality = cloud.quality.empty() ? nullptr : cloud.quality.data();
    const float* intensity = cloud.intensity.empty() ? nullptr : cloud.intensity.data();
    const float* sigma_z = cloud.sigma_z.empty() ? nullptr : cloud.sigma_z.data();
    const std::size_t record = record_bytes(cloud);
    std::size_t done = 0;
    std::size_t i = pixel;
    for (const std::size_t count = cloud.xyz.pixel_count(); i < count && done < max_points; ++i) {
        const float* p = xyz + 3 * i;
        if (!has_point(p))
            continue;
        put_f32(out, p[0]);
        put_f32(out + 4, p[1]);
        put_f32(out + 8, p[2]);
        put_f32(out + 12, quality ? quality[i] : nan);
        put_f32(out + 16, intensity ? intensity[i] : nan);
        if (sigma_z)
            put_f32(out + 20, sigma_z[i]);
        put_u32(out + record - 4, static_cast<std::uint32_t>(i));
        out += record;
        ++done;
    }
    pixel = i;
    return done;
}

// Records encoded at a time by write_ply_synced: 1.5 MiB pieces (1.75 MiB
// with sigma_z), so that its buffers stay small and reused while the file is
// written.
constexpr std::size_t kChunkPoints = 65536;

// Writes pieces to a file, in order, on a thread of its own, from a ring of
// buffers the caller fills: the caller encodes the next pieces while the
// previous ones are copied into the page cache by write().
class BackgroundWriter {
public:
    BackgroundWriter(SyncedFileWriter& out, std::size_t buffer_bytes) : out_(out) {
        for (auto& b : buffers_)
            b.resize(buffer_bytes);
        thread_ = std::thread([this] { run(); });
    }
    // Abandons the pieces not yet written (after drain(): none).
    ~BackgroundWriter() {
        {
            const std::lock_guard lock(mutex_);
            stop_ = true;
        }
        changed_.notify_all();
        thread_.join();
    }
    BackgroundWriter(const BackgroundWriter&) = delete;
    BackgroundWriter& operator=(const BackgroundWriter&) = delete;

    // The buffer to fill next, once one is free. Rethrows a write error.
    char* next_buffer() {
        std::unique_lock lock(mutex_);
        changed_.wait(lock, [&] { return error_ || queued_ < kBuffers; });
        if (error_)
            std::rethrow_exception(error_);
        return buffers_[(first_ + queued_) % kBuffers].data();
    }
    // Queues the buffer returned by next_buffer(), filled with `bytes`.
    void submit(std::size_t bytes) {
        {
            const std::lock_guard lock(mutex_);
            sizes_[(first_ + queued_) % kBuffers] = bytes;
            ++queued_;
        }
        changed_.notify_all();
    }
    // Waits until every queued piece is written. Rethrows a write error.
    void drain() {
        std::unique_lock lock(mutex_);
        changed_.wait(lock, [&] { return error_ || queued_ == 0; });
        if (error_)
            std::rethrow_exception(error_);
    }

private:
    static constexpr std::size_t kBuffers = 3;

    void run() {
        std::unique_lock lock(mutex_);
        for (;;) {
            changed_.wait(lock, [&] { return stop_ || queued_ > 0; });
            if (stop_)
                return;
            const std::size_t i = first_;
            lock.unlock();
            try {
                out_.write({buffers_[i].data(), sizes_[i]});
            } catch (...) {
                lock.lock();
                error_ = std::current_exception();
                changed_.notify_all();
                return;
            }
            lock.lock();
            first_ = (first_ + 1) % kBuffers;
            --queued_;
            changed_.notify_all();
        }
    }

    SyncedFileWriter& out_;
    std::array<std::vector<char>, kBuffers> buffers_;
    std::array<std::size_t, kBuffers> sizes_{};
    std::mutex mutex_;
    std::condition_variable changed_;
    std::size_t first_ = 0;  // oldest queued buffer
    std::size_t queued_ = 0; // buffers queued or being written
    bool stop_ = false;
    std::exception_ptr error_;
    std::thread thread_; // last: started once the rest is built
};

} // namespace

std::string encode_ply(const PointCloud& cloud, const std::vector<std::string>& comments) {
    check_cloud(cloud);
    const std::size_t points = cloud.count_points();
    std::string bytes = ply_header(cloud, comments, points);
    const std::size_t body = bytes.size();
    bytes.resize(body + points * record_bytes(cloud));
    std::size_t pixel = 0;
    encode_records(cloud, pixel, bytes.data() + body, points);
    return bytes;
}

void write_ply_synced(const std::filesystem::path& path, const PointCloud& cloud,
                      const std::vector<std::string>& comments) {
    check_cloud(cloud);
    const std::size_t points = cloud.count_points();
    SyncedFileWriter out(path);
    out.write(ply_header(cloud, comments, points));
    {
        const std::size_t record = record_bytes(cloud);
        BackgroundWriter writer(out, kChunkPoints * record);
        std::size_t pixel = 0;
        for (std::size_t left = points; left > 0;) {
            const std::size_t n = encode_records(cloud, pixel, writer.next_buffer(), kChunkPoints);
            writer.submit(n * record);
            left -= n;
        }
        writer.drain();
    }
    out.finish();
}

void write_ply(const std::filesystem::path& path, const PointCloud& cloud,
               const std::vector<std::string>& comments) {
    check_cloud(cloud);
    write_atomically(
        path, [&](const std::filesystem::path& temp) { write_ply_synced(temp, cloud, comments); });
}

namespace {

enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };

bool parse_type(const std::string& name, PlyType& type) {
    static const struct {
        const char* old_name;
        const char* new_name;
        PlyType type;
    } kTypes[] = {{"char", "int8", PlyType::i8},      {"uchar", "uint8", PlyType::u8},
                  {"short", "int16", PlyType::i16},   {"ushort", "uint16", PlyType::u16},
                  {"int", "int32", PlyType::i32},     {"uint", "uint32", PlyType::u32},
                  {"float", "float32", PlyType::f32}, {"double", "float64", PlyType::f64}};
    for (const auto& t : kTypes)
        if (name == t.old_name || name == t.new_name) {
            type = t.type;
            return true;
        }
    return false;
}

std::size_t type_bytes(PlyType t) {
    switch (t) {
    case PlyType::i8:
    case PlyType::u8:
        return 1;
    case PlyType::i16:
    case PlyType::u16:
        return 2;
    case PlyType::i32:
    case PlyType::u32:
    case PlyType::f32:
        return 4;
    case PlyType::f64:
        return 8;
    }
    return 0;
}

template <class T> T load_le(const char* p) {
    T v;
    std::memcpy(&v, p, sizeof(T));
    if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) {
        using U =
            std::conditional_t<sizeof(T) == 2, std::uint16_t,
                               std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>;
        v = std::bit_cast<T>(swap_bytes(std::bit_cast<U>(v)));
    }
    return v;
}

double load_value(const char* p, PlyType t) {
    switch (t) {
    case PlyType::i8:
        return load_le<std::int8_t>(p);
    case PlyType::u8:
        return load_le<std::uint8_t>(p);
    case PlyType::i16:
        return load_le<std::int16_t>(p);
    case PlyType::u16:
        return load_le<std::uint16_t>(p);
    case PlyType::i32:
        return load_le<std::int32_t>(p);
    case PlyType::u32:
        return load_le<std::uint32_t>(p);
    case PlyType::f32:
        return double(load_le<float>(p));
    case PlyType::f64:
        return load_le<double>(p);
    }
    return 0;
}

struct PlyProperty {
    std::string name;
    PlyType type;
    std::size_t offset; // in the vertex record
};

// What the header says of the vertex element.
struct PlyHeader {
    std::vector<PlyProperty> props;
    std::size_t vertex_count = 0;
    std::size_t record = 0; // bytes per vertex
    std::size_t body = 0;   // offset of the first vertex in the file
};

// Header lines, one at a time, up to and including "end_header".
class PlyHeaderLines {
public:
    PlyHeaderLines(const std::string& bytes, const std::filesystem::path& path)
        : bytes_(bytes), path_(path) {}

    void next(std::string& line) {
        const std::size_t end = bytes_.find('\n', pos_);
        if (end == std::string::npos)
            throw InputError(path_, "header", "no end_header line");
        line = bytes_.substr(pos_, end - pos_);
        if (!line.empty() && line.back() == '\r')
            line.pop_back();
        pos_ = end + 1;
    }
    std::size_t position() const { return pos_; }

private:
    const std::string& bytes_;
    const std::filesystem::path& path_;
    std::size_t pos_ = 0;
};

// Reads the header: the vertex element's properties and count, comments and
// the organised size (into `points`); checks the format.
PlyHeader read_ply_header(const std::string& bytes, const std::filesystem::path& path,
                          PlyPoints& points) {
    PlyHeaderLines lines(bytes, path);
    std::string line;
    lines.next(line);
    if (line != "ply")
        throw InputError(path, "header", "not a PLY file (first line is not 'ply')");

    PlyHeader header;
    int element_index = -1;
    bool format_seen = false;
    long long organised_w = -1, organised_h = -1;
    for (;;) {
        lines.next(line);
        std::istringstream words(line);
        std::string keyword;
        words >> keyword;
        if (keyword == "end_header")
            break;
        if (keyword == "comment") {
            points.comments.push_back(line.size() > 8 ? line.substr(8) : std::string());
        } else if (keyword == "obj_info") {
            std::string key;
            long long value = -1;
            words >> key >> value;
            if (key == "organised_width")
                organised_w = value;
            if (key == "organised_height")
                organised_h = value;
        } else if (keyword == "format") {
            std::string encoding, version;
            words >> encoding >> version;
            if (encoding != "binary_little_endian")
                throw InputError(path, "format",
                                 "only binary_little_endian PLY is read, not '" + encoding + "'");
            format_seen = true;
        } else if (keyword == "element") {
            std::string name;
            long long count = -1;
            words >> name >> count;
            ++element_index;
            if (element_index == 0) {
                if (name != "vertex")
                    throw InputError(path, "element", "the first element must be 'vertex'");
                if (count < 0 || words.fail())
                    throw InputError(path, "element vertex", "bad vertex count");
                header.vertex_count = static_cast<std::size_t>(count);
            }
        } else if (keyword == "property") {
            if (element_index < 0)
                throw InputError(path, "property", "property before any element");
            if (element_index > 0)
                continue; // properties of later elements: ignored
            std::string type_name, name;
            words >> type_name >> name;
            if (type_name == "list")
                throw InputError(path, "property", "list properties in 'vertex' are not supported");
            PlyType type{};
            if (!parse_type(type_name, type) || name.empty())
                throw InputError(path, "property", "bad property line '" + line + "'");
            header.props.push_back({name, type, header.record});
            header.record += type_bytes(type);
        } else {
            throw InputError(path, "header", "unknown header line '" + line + "'");
        }
    }
    if (!format_seen)
        throw InputError(path, "format", "missing format line");
    if (element_index < 0)
        throw InputError(path, "element", "no vertex element");
    if (organised_w > 0 && organised_h > 0 && organised_w <= std::numeric_limits<int>::max() &&
        organised_h <= std::numeric_limits<int>::max())
        points.organised = {static_cast<int>(organised_w), static_cast<int>(organised_h)};
    header.body = lines.position();
    return header;
}

// Reads the vertices after the header: x, y, z and whichever of quality,
// intensity, sigma_z and pixel the header lists.
void read_ply_body(const std::string& bytes, const PlyHeader& header,
                   const std::filesystem::path& path, PlyPoints& points) {
    const PlyProperty* px = nullptr;
    const PlyProperty* py = nullptr;
    const PlyProperty* pz = nullptr;
    const PlyProperty* pq = nullptr;
    const PlyProperty* pi = nullptr;
    const PlyProperty* ps = nullptr;
    const PlyProperty* pp = nullptr;
    for (const auto& p : header.props) {
        if (p.name == "x")
            px = &p;
        if (p.name == "y")
            py = &p;
        if (p.name == "z")
            pz = &p;
        if (p.name == "quality")
            pq = &p;
        if (p.name == "intensity")
            pi = &p;
        if (p.name == "sigma_z")
            ps = &p;
        if (p.name == "pixel")
            pp = &p;
    }
    const std::size_t vertex_count = header.vertex_count;
    const std::size_t record = header.record;
    if (!px || !py || !pz)
        throw InputError(path, "element vertex", "no x, y, z properties");
    if (record == 0 || (bytes.size() - header.body) / record < vertex_count)
        throw InputError(path, "element vertex",
                         "truncated: " + std::to_string(vertex_count) + " vertices of " +
                             std::to_string(record) + " bytes need more than the file holds");

    points.x.resize(vertex_count);
    points.y.resize(vertex_count);
    points.z.resize(vertex_count);
    if (pq)
        points.quality.resize(vertex_count);
    if (pi)
        points.intensity.resize(vertex_count);
    if (ps)
        points.sigma_z.resize(vertex_count);
    if (pp)
        points.pixel.resize(vertex_count);
    const char* base = bytes.data() + header.body;
    for (std::size_t i = 0; i < vertex_count; ++i, base += record) {
        points.x[i] = static_cast<float>(load_value(base + px->offset, px->type));
        points.y[i] = static_cast<float>(load_value(base + py->offset, py->type));
        points.z[i] = static_cast<float>(load_value(base + pz->offset, pz->type));
        if (pq)
            points.quality[i] = static_cast<float>(load_value(base + pq->offset, pq->type));
        if (pi)
            points.intensity[i] = static_cast<float>(load_value(base + pi->offset, pi->type));
        if (ps)
            points.sigma_z[i] = static_cast<float>(load_value(base + ps->offset, ps->type));
        if (pp) {
            const double v = load_value(base + pp->offset, pp->type);
            if (!(v >= 0 && v <= double(std::numeric_limits<std::uint32_t>::max())))
                throw InputError(path, "pixel",
                                 "vertex " + std::to_string(i) + ": bad pixel index");
            points.pixel[i] = static_cast<std::uint32_t>(v);
        }
    }
}

} // namespace

PlyPoints read_ply(const std::filesystem::path& path) {
    const std::string bytes = yaml_fields::read_text_file(path); // binary-safe
    PlyPoints points;
    const PlyHeader header = read_ply_header(bytes, path, points);
    read_ply_body(bytes, header, path, points);
    return points;
}

std::size_t drop_points_above_sigma(PointCloud& cloud, float max_sigma_z_mm) {
    if (!(max_sigma_z_mm > 0))
        throw std::invalid_argument("drop_points_above_sigma: the limit must be > 0 mm");
    if (cloud.xyz.channels() != 3 || cloud.sigma_z.channels() != 1 ||
        cloud.sigma_z.size() != cloud.xyz.size() || cloud.sigma_z.empty())
        throw std::invalid_argument(
            "drop_points_above_sigma: the cloud has no sigma_z of its size");
    constexpr float nan = std::numeric_limits<float>::quiet_NaN();
    float* xyz = cloud.xyz.data();
    float* sigma = cloud.sigma_z.data();
    std::size_t dropped = 0;
    for (std::size_t i = 0, count = cloud.xyz.pixel_count(); i < count; ++i) {
        float* p = xyz + 3 * i;
        if (!(sigma[i] > max_sigma_z_mm) || !has_point(p))
            continue;
        p[0] = p[1] = p[2] = nan;
        sigma[i] = nan;
        ++dropped;
    }
    return dropped;
}

} // namespace fpp
