#pragma once
// Every coefficient of two lens models equal, exactly (a file's round trip,
// a conversion that must not touch the model).
#include "fpp/lens_model.hpp"

#include <gtest/gtest.h>

namespace fpp::test {

inline void expect_same_lens(const LensModel& a, const LensModel& b) {
    EXPECT_EQ(a.fu, b.fu);
    EXPECT_EQ(a.fv, b.fv);
    EXPECT_EQ(a.cu, b.cu);
    EXPECT_EQ(a.cv, b.cv);
    EXPECT_EQ(a.skew, b.skew);
    EXPECT_EQ(a.k1, b.k1);
    EXPECT_EQ(a.k2, b.k2);
    EXPECT_EQ(a.k3, b.k3);
    EXPECT_EQ(a.p1, b.p1);
    EXPECT_EQ(a.p2, b.p2);
    EXPECT_EQ(a.k4, b.k4);
    EXPECT_EQ(a.s1, b.s1);
    EXPECT_EQ(a.s2, b.s2);
    EXPECT_EQ(a.s3, b.s3);
    EXPECT_EQ(a.s4, b.s4);
    EXPECT_EQ(a.t1, b.t1);
    EXPECT_EQ(a.t2, b.t2);
    EXPECT_EQ(a.dc_k1, b.dc_k1);
    EXPECT_EQ(a.dc_k2, b.dc_k2);
    EXPECT_EQ(a.dc_x, b.dc_x);
    EXPECT_EQ(a.dc_y, b.dc_y);
}

} // namespace fpp::test
