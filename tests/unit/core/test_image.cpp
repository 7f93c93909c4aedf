// The owning image, the captured frame and the borrowed frame view
// (fpp/image.hpp): layout (rows of interleaved channels, no padding), copies
// and moves, and a frame's full scale from its bits in use.

#include "fpp/image.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <utility>

namespace {

using fpp::Frame;
using fpp::FrameView;
using fpp::Image;
using fpp::Size;

TEST(Image, RowsOfInterleavedChannelsWithoutPadding) {
    Image<int> image(4, 3, 2, 7);
    EXPECT_EQ(image.width(), 4);
    EXPECT_EQ(image.height(), 3);
    EXPECT_EQ(image.channels(), 2);
    EXPECT_EQ(image.size(), (Size{4, 3}));
    EXPECT_EQ(image.pixel_count(), 12u);
    ASSERT_EQ(image.storage().size(), 24u);
    for (const int v : image.storage())
        EXPECT_EQ(v, 7);
    image.at(3, 2, 1) = 9; // pixel (3, 2): row 2 starts at 2 * 4 * 2, channel 1 of pixel 3
    EXPECT_EQ(image.storage()[(2 * 4 + 3) * 2 + 1], 9);
    EXPECT_EQ(image.row(2) - image.data(), 16);
    EXPECT_EQ(image.row(2)[3 * 2 + 1], 9);
    const Image<int>& same = image;
    EXPECT_EQ(same.at(3, 2, 1), 9);
    EXPECT_EQ(same.at(3, 2, 0), 7);
}

TEST(Image, SizeConstructorAndArea) {
    const Image<float> image(Size{5, 2}, 3, 0.5f);
    EXPECT_EQ(image.size(), (Size{5, 2}));
    EXPECT_EQ(image.storage().size(), 30u);
    EXPECT_EQ(image.at(4, 1, 2), 0.5f);
    EXPECT_EQ((Size{1600, 1200}).area(), 1920000u);
    EXPECT_EQ((Size{0, 7}).area(), 0u);
    EXPECT_TRUE(Image<int>().empty());
    EXPECT_EQ(Image<int>().channels(), 1);
}

TEST(Image, CopiesAreDeep) {
    Image<std::uint8_t> a(2, 2, 1, 1);
    Image<std::uint8_t> b = a;
    b.at(1, 1) = 200;
    EXPECT_EQ(a.at(1, 1), 1);
    a = b;
    EXPECT_EQ(a.at(1, 1), 200);
    EXPECT_NE(a.data(), b.data());
}

TEST(Image, AMovedFromImageIsEmptyWithSizeZero) {
    Image<std::uint16_t> a(6, 4, 3, 42);
    const std::uint16_t* pixels = a.data();
    Image<std::uint16_t> b(std::move(a));
    EXPECT_EQ(b.size(), (Size{6, 4}));
    EXPECT_EQ(b.channels(), 3);
    EXPECT_EQ(b.data(), pixels); // the pixels moved, not copied
    EXPECT_EQ(b.at(5, 3, 2), 42);
    // NOLINTBEGIN(bugprone-use-after-move): the moved-from state is specified
    EXPECT_TRUE(a.empty());
    EXPECT_EQ(a.size(), (Size{0, 0}));
    EXPECT_EQ(a.channels(), 1);
    EXPECT_EQ(a.pixel_count(), 0u);

    Image<std::uint16_t> c(1, 1);
    c = std::move(b);
    EXPECT_EQ(c.size(), (Size{6, 4}));
    EXPECT_EQ(c.data(), pixels);
    EXPECT_TRUE(b.empty());
    EXPECT_EQ(b.size(), (Size{0, 0}));
    EXPECT_EQ(b.channels(), 1);
    // NOLINTEND(bugprone-use-after-move)
}

TEST(Frame, SizeAndFullScaleFollowTheDepthAndTheBitsInUse) {
    Frame eight;
    eight.u8 = Image<std::uint8_t>(8, 6);
    EXPECT_EQ(eight.size(), (Size{8, 6}));
    EXPECT_EQ(eight.max_value(), 255);
    Frame sixteen;
    sixteen.bit_depth = 16;
    sixteen.u16 = Image<std::uint16_t>(3, 2);
    EXPECT_EQ(sixteen.size(), (Size{3, 2}));
    EXPECT_EQ(sixteen.max_value(), 65535);
    sixteen.significant_bits = 12; // a 12-bit sensor stored in 16 bits
    EXPECT_EQ(sixteen.max_value(), 4095);
    sixteen.significant_bits = 10;
    EXPECT_EQ(sixteen.max_value(), 1023);
}

TEST(FrameView, BorrowsAFramesSamplesWithoutCopying) {
    Frame frame;
    frame.bit_depth = 16;
    frame.significant_bits = 12;
    frame.u16 = Image<std::uint16_t>(5, 4, 1, 300);
    frame.u16.at(4, 3) = 4095;
    const FrameView view = frame;
    EXPECT_EQ(view.bit_depth, 16);
    EXPECT_EQ(view.size, (Size{5, 4}));
    EXPECT_EQ(view.channels, 1);
    EXPECT_EQ(view.data, frame.u16.data());
    EXPECT_FALSE(view.empty());
    EXPECT_EQ(view.sample_count(), 20u);
    EXPECT_EQ(view.u16()[19], 4095);
    EXPECT_EQ(view.max_value(), 4095);

    Frame eight;
    eight.u8 = Image<std::uint8_t>(2, 2, 3, 9); // interleaved samples
    const FrameView colour = eight;
    EXPECT_EQ(colour.channels, 3);
    EXPECT_EQ(colour.sample_count(), 12u);
    EXPECT_EQ(colour.u8(), eight.u8.data());
    EXPECT_EQ(colour.max_value(), 255);
}

TEST(FrameView, AFrameWithoutSamplesIsAnEmptyView) {
    const FrameView none = Frame{};
    EXPECT_TRUE(none.empty());
    EXPECT_EQ(none.data, nullptr);
    EXPECT_EQ(none.sample_count(), 0u);
    Frame sixteen;
    sixteen.bit_depth = 16;
    sixteen.u8 = Image<std::uint8_t>(4, 4); // the wrong container: not the view's
    EXPECT_TRUE(FrameView(sixteen).empty());
    EXPECT_EQ(FrameView(sixteen).size, (Size{0, 0}));
    EXPECT_TRUE(FrameView().empty());
}

} // namespace
