// xray_frames.png's columns and their time labels (XrayFramesLayout.h), against indices and strings worked out by
// hand.
#include "cementsph/rendering/XrayFramesLayout.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <vector>

namespace {
using cementsph::rendering::xrayFrameColumns;
using cementsph::rendering::xrayTimeLabel;
using Columns = std::vector<std::size_t>;

TEST(XrayFramesLayout, ColumnsSpreadEvenlyWithFirstAndLast) {
  // 21 frames in 8 columns: round(k x 20 / 7) for k = 0..7 = 0, 2.86, 5.71, 8.57, 11.43, 14.29, 17.14, 20.
  EXPECT_EQ(xrayFrameColumns(21, 8), (Columns{0, 3, 6, 9, 11, 14, 17, 20}));
  // Fewer frames than columns: every frame once.
  EXPECT_EQ(xrayFrameColumns(3, 8), (Columns{0, 1, 2}));
  // maxColumns below 2 still shows the first and the last.
  EXPECT_EQ(xrayFrameColumns(5, 1), (Columns{0, 4}));
}

TEST(XrayFramesLayout, ColumnsOfFewerThanTwoFrames) {
  EXPECT_EQ(xrayFrameColumns(1, 8), (Columns{0}));
  EXPECT_TRUE(xrayFrameColumns(0, 8).empty());
}

TEST(XrayFramesLayout, TimeLabelHasOneDecimalAndNoNegativeZero) {
  EXPECT_EQ(xrayTimeLabel(12.46), "t = 12.5 s");
  EXPECT_EQ(xrayTimeLabel(-0.04), "t = 0.0 s");
  EXPECT_EQ(xrayTimeLabel(0.0), "t = 0.0 s");
  EXPECT_EQ(xrayTimeLabel(-1.0), "t = -1.0 s");
}

} // namespace
