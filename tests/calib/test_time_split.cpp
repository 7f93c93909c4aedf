// Where a command's time goes (fpp/calib/time_split.hpp): seconds summed per
// stage in the order the stages first ran, splits merged, the one-line
// summary, and the stage timer adding its time once.

#include "fpp/calib/time_split.hpp"

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

using fpp::calib::StageTimer;
using fpp::calib::TimeSplit;

namespace {

using Stages = std::vector<std::pair<std::string, double>>;

TEST(TimeSplit, SecondsAddUpPerStageInTheOrderTheStagesFirstRan) {
    TimeSplit split;
    EXPECT_TRUE(split.stages().empty());
    EXPECT_EQ(split.summary(), "");
    split.add("reading", 7.25);
    split.add("decoding", 1.0);
    split.add("reading", 0.0625);
    split.add("fitting", 0.5);
    EXPECT_EQ(split.stages(), (Stages{{"reading", 7.3125}, {"decoding", 1.0}, {"fitting", 0.5}}));
    EXPECT_EQ(split.seconds("reading"), 7.3125);
    EXPECT_EQ(split.seconds("never ran"), 0.0);
}

TEST(TimeSplit, SummaryIsOneLineInHundredths) {
    TimeSplit split;
    split.add("reading", 7.3125);
    split.add("decoding", 1.2);
    split.add("writing", 0.004);
    EXPECT_EQ(split.summary(), "reading 7.31 s, decoding 1.20 s, writing 0.00 s");
}

TEST(TimeSplit, AnotherSplitAddsItsStagesInItsOrder) {
    TimeSplit command;
    command.add("reading", 1.0);
    TimeSplit pose; // a pose's stages, e.g. from another thread
    pose.add("decoding", 2.0);
    pose.add("reading", 0.5);
    pose.add("corners", 0.25);
    command.add(pose);
    command.add(pose);
    EXPECT_EQ(command.stages(), (Stages{{"reading", 2.0}, {"decoding", 4.0}, {"corners", 0.5}}));
}

TEST(StageTimer, AddsItsTimeOnceWhenStoppedOrDestroyed) {
    TimeSplit split;
    double stopped = -1;
    {
        StageTimer timer(split, "decoding");
        stopped = timer.stop();
        EXPECT_GE(stopped, 0.0);
        EXPECT_EQ(timer.stop(), 0.0); // already stopped: nothing more
    }                                 // nor at destruction
    ASSERT_EQ(split.stages().size(), 1u);
    EXPECT_EQ(split.seconds("decoding"), stopped);
    { const StageTimer timer(split, "writing"); } // added when it goes out of scope
    ASSERT_EQ(split.stages().size(), 2u);
    EXPECT_EQ(split.stages()[1].first, "writing");
    EXPECT_GE(split.seconds("writing"), 0.0);
    {
        StageTimer again(split, "decoding"); // the same stage: summed
        const double more = again.stop();
        EXPECT_EQ(split.seconds("decoding"), stopped + more);
    }
    EXPECT_EQ(split.stages().size(), 2u);
}

} // namespace
