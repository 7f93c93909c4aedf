// GigE Vision frame ids (fpp/drivers/gige_frame_ids.hpp): the next id and
// the frames lost between two ids, across the 16-bit wrap (which skips the
// reserved 0) and with 64-bit extended ids; repeats and steps back.

#include "fpp/drivers/gige_frame_ids.hpp"

#include <gtest/gtest.h>

#include <cstdint>

using fpp::drivers::gige_frames_missed;
using fpp::drivers::gige_next_frame_id;

TEST(GigeFrameIds, CountGapsAcrossThe16BitWrap) {
    EXPECT_EQ(gige_next_frame_id(41u), 42u);
    EXPECT_EQ(gige_next_frame_id(65535u), 1u);     // 0 is reserved
    EXPECT_EQ(gige_next_frame_id(65536u), 65537u); // extended 64-bit ids do not wrap
    EXPECT_EQ(gige_frames_missed(41, 42), 0u);
    EXPECT_EQ(gige_frames_missed(41, 44), 2u);
    EXPECT_EQ(gige_frames_missed(65535, 1), 0u);
    EXPECT_EQ(gige_frames_missed(65534, 1), 1u);
    EXPECT_EQ(gige_frames_missed(65530, 3), 7u);
    EXPECT_EQ(gige_frames_missed(42, 42), UINT64_MAX); // repeat
    EXPECT_EQ(gige_frames_missed(42, 40), UINT64_MAX); // step back
    EXPECT_EQ(gige_frames_missed(65535, 0), UINT64_MAX);
    EXPECT_EQ(gige_frames_missed(70000, 70001), 0u);
}

TEST(GigeFrameIds, EveryIdFollowedByItsNextMissesNothing) {
    // Every 16-bit id, and the first extended ones past 16 bits.
    for (std::uint64_t id = 1; id <= 0x10010u; ++id)
        ASSERT_EQ(gige_frames_missed(id, gige_next_frame_id(id)), 0u) << id;
    static_assert(gige_next_frame_id(0xFFFFu) == 1u);
    static_assert(gige_frames_missed(0xFFFFu, 1u) == 0u);
}

TEST(GigeFrameIds, SkippedIdsAreCountedOnEitherSideOfTheWrap) {
    // k ids skipped after `previous`, counted the way the camera counts.
    for (const std::uint64_t previous : {1u, 1000u, 65500u, 65534u, 65535u})
        for (std::uint64_t k = 0; k < 100; ++k) {
            std::uint64_t id = previous;
            for (std::uint64_t i = 0; i <= k; ++i)
                id = gige_next_frame_id(id);
            ASSERT_EQ(gige_frames_missed(previous, id), k) << previous << " -> " << id;
        }
}

TEST(GigeFrameIds, AWrapNeedsAStepBackOfMoreThanHalfThe16BitRange) {
    // 32770 -> 1: ids 32771 .. 65535 missing, 32765 of them.
    EXPECT_EQ(gige_frames_missed(0x8002u, 1u), 0xFFFFu - 0x8002u);
    EXPECT_EQ(gige_frames_missed(0x8002u, 1u), 32765u);
    // 32769 -> 1 is a step back of exactly half the range: not a wrap.
    EXPECT_EQ(gige_frames_missed(0x8001u, 1u), UINT64_MAX);
    // Extended ids never wrap: a smaller one is a step back however far.
    EXPECT_EQ(gige_frames_missed(0x20000u, 0x10000u), UINT64_MAX);
    EXPECT_EQ(gige_frames_missed(70000u, 69999u), UINT64_MAX);
    // A 64-bit id past a 16-bit one: the ids between are missing.
    EXPECT_EQ(gige_frames_missed(65535u, 65537u), 1u);
}
