// What simulated devices record for tests (fpp/sim/record_log.hpp):
// everything while unlimited; past a limit the oldest half dropped at once,
// the newest kept in order and every record counted.

#include "fpp/sim/record_log.hpp"

#include <gtest/gtest.h>

#include <cstddef>
#include <vector>

using fpp::sim::RecordLog;

namespace {

std::vector<int> range(int first, int last) {
    std::vector<int> v;
    for (int i = first; i <= last; ++i)
        v.push_back(i);
    return v;
}

TEST(RecordLog, UnlimitedKeepsEverything) {
    RecordLog<int> log;
    EXPECT_TRUE(log.empty());
    EXPECT_EQ(log.total(), 0u);
    for (int i = 1; i <= 5000; ++i)
        log.push(i);
    EXPECT_FALSE(log.empty());
    EXPECT_EQ(log.items(), range(1, 5000));
    EXPECT_EQ(log.total(), 5000u);
    EXPECT_EQ(log.back(), 5000);
}

TEST(RecordLog, PastTheLimitTheOldestHalfGoesAtOnce) {
    RecordLog<int> log;
    log.set_limit(4);
    for (int i = 1; i <= 4; ++i)
        log.push(i);
    EXPECT_EQ(log.items(), range(1, 4));
    log.push(5); // 4 kept at the limit: down to 2, then the new one
    EXPECT_EQ(log.items(), range(3, 5));
    EXPECT_EQ(log.total(), 5u);
    log.push(6);
    EXPECT_EQ(log.items(), range(3, 6));
    log.push(7);
    EXPECT_EQ(log.items(), range(5, 7));
    EXPECT_EQ(log.total(), 7u);
    EXPECT_EQ(log.back(), 7);
}

TEST(RecordLog, ALimitSetLateTrimsAtTheNextPush) {
    RecordLog<int> log;
    for (int i = 1; i <= 10; ++i)
        log.push(i);
    log.set_limit(4);
    EXPECT_EQ(log.items().size(), 10u); // nothing dropped until a push
    log.push(11);
    EXPECT_EQ(log.items(), range(9, 11));
    EXPECT_EQ(log.total(), 11u);
}

TEST(RecordLog, TheLimitIsAtLeastTwo) {
    for (const std::size_t limit : {std::size_t(0), std::size_t(1), std::size_t(2)}) {
        RecordLog<int> log;
        log.set_limit(limit);
        for (int i = 1; i <= 3; ++i)
            log.push(i);
        EXPECT_EQ(log.items(), range(2, 3)) << limit;
        EXPECT_EQ(log.total(), 3u) << limit;
    }
}

TEST(RecordLog, AMonthOfRecordsStaysWithinTheLimit) {
    RecordLog<int> log;
    log.set_limit(1024);
    const int pushed = 100'000;
    for (int i = 1; i <= pushed; ++i) {
        log.push(i);
        ASSERT_LE(log.items().size(), 1024u);
    }
    EXPECT_EQ(log.total(), std::size_t(pushed));
    // The newest, consecutive, oldest first.
    const std::vector<int>& kept = log.items();
    EXPECT_GE(kept.size(), 512u);
    for (std::size_t i = 0; i < kept.size(); ++i)
        ASSERT_EQ(kept[i], pushed - int(kept.size() - 1 - i));
}

} // namespace
