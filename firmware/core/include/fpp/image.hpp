#pragma once
// A small owning image: contiguous rows, interleaved channels, no padding.
// (FrameView below borrows a frame's samples instead.)
// Pixel (x, y) has its centre at integer coordinates (x, y).

#include <cassert>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace fpp {

struct Size {
    int width = 0;
    int height = 0;
    friend bool operator==(const Size&, const Size&) = default;
    std::size_t area() const { return std::size_t(width) * std::size_t(height); }
};

template <class T> class Image {
public:
    Image() = default;
    Image(int width, int height, int channels = 1, T fill = T{})
        : width_(width), height_(height), channels_(channels),
          data_(std::size_t(width) * std::size_t(height) * std::size_t(channels), fill) {}
    Image(Size size, int channels = 1, T fill = T{})
        : Image(size.width, size.height, channels, fill) {}
    Image(const Image&) = default;
    Image& operator=(const Image&) = default;
    // A moved-from image is empty with size 0x0, not a size without pixels.
    Image(Image&& other) noexcept
        : width_(std::exchange(other.width_, 0)), height_(std::exchange(other.height_, 0)),
          channels_(std::exchange(other.channels_, 1)), data_(std::move(other.data_)) {
        other.data_.clear();
    }
    Image& operator=(Image&& other) noexcept {
        if (this == &other)
            return *this;
        width_ = std::exchange(other.width_, 0);
        height_ = std::exchange(other.height_, 0);
        channels_ = std::exchange(other.channels_, 1);
        data_ = std::move(other.data_);
        other.data_.clear();
        return *this;
    }

    int width() const { return width_; }
    int height() const { return height_; }
    int channels() const { return channels_; }
    Size size() const { return {width_, height_}; }
    bool empty() const { return data_.empty(); }
    std::size_t pixel_count() const { return std::size_t(width_) * std::size_t(height_); }

    T* data() { return data_.data(); }
    const T* data() const { return data_.data(); }
    T* row(int y) { return data_.data() + std::size_t(y) * std::size_t(width_) * channels_; }
    const T* row(int y) const {
        return data_.data() + std::size_t(y) * std::size_t(width_) * channels_;
    }
    T& at(int x, int y, int c = 0) {
        assert(x >= 0 && x < width_ && y >= 0 && y < height_ && c >= 0 && c < channels_);
        return row(y)[std::size_t(x) * channels_ + c];
    }
    const T& at(int x, int y, int c = 0) const {
        assert(x >= 0 && x < width_ && y >= 0 && y < height_ && c >= 0 && c < channels_);
        return row(y)[std::size_t(x) * channels_ + c];
    }
    std::vector<T>& storage() { return data_; }
    const std::vector<T>& storage() const { return data_; }

private:
    int width_ = 0;
    int height_ = 0;
    int channels_ = 1;
    std::vector<T> data_;
};

// A camera frame as captured: 8-bit or 16-bit samples, single channel.
// 8-bit frames are stored in u8, 16-bit in u16; exactly one is non-empty.
struct Frame {
    int bit_depth = 8; // 8 or 16 (container depth; a 12-bit sensor uses 16)
    Image<std::uint8_t> u8;
    Image<std::uint16_t> u16;

    Size size() const { return bit_depth == 8 ? u8.size() : u16.size(); }
    // Bits in use, LSB-aligned (a 12-bit camera stored in 16 bits: 12); 0 =
    // the container's. Full scale (saturation, modulation floors) follows it.
    int significant_bits = 0;
    int max_value() const {
        const int bits = significant_bits > 0 ? significant_bits : bit_depth;
        return (1 << bits) - 1;
    }
};

// A camera frame's samples borrowed, not owned (the decoder's input): memory
// the caller keeps alive and unchanged while the view is used, rows
// contiguous, no padding. Made from a Frame (implicitly: its pixels, no copy)
// or from any such buffer (a NumPy array from Python).
struct FrameView {
    int bit_depth = 8;          // 8: data holds std::uint8_t, 16: std::uint16_t
    Size size;                  // width x height samples
    int channels = 1;           // interleaved samples per pixel (a frame has 1)
    const void* data = nullptr; // null when there are no samples
    int significant_bits = 0;   // as Frame::significant_bits

    FrameView() = default;
    FrameView(const Frame& frame) // NOLINT(google-explicit-constructor): a view of it
        : bit_depth(frame.bit_depth), size(frame.size()),
          channels(frame.bit_depth == 8 ? frame.u8.channels() : frame.u16.channels()),
          significant_bits(frame.significant_bits) {
        const bool eight = frame.bit_depth == 8;
        if (!(eight ? frame.u8.empty() : frame.u16.empty()))
            data = eight ? static_cast<const void*>(frame.u8.data())
                         : static_cast<const void*>(frame.u16.data());
    }

    bool empty() const { return data == nullptr; }
    const std::uint8_t* u8() const { return static_cast<const std::uint8_t*>(data); }
    const std::uint16_t* u16() const { return static_cast<const std::uint16_t*>(data); }
    std::size_t sample_count() const { return size.area() * std::size_t(channels); }
    int max_value() const {
        const int bits = significant_bits > 0 ? significant_bits : bit_depth;
        return (1 << bits) - 1;
    }
};

} // namespace fpp
