// VirtualDisplay: a user on a headless machine gets a working X display without knowing about Xvfb.
#include "RenderingTestSupport.h"

#include "cementsph/rendering/VirtualDisplay.h"

#include <X11/Xlib.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

using cementsph::rendering::VirtualDisplay;

namespace {
bool canOpen(const std::string& name) {
  Display* display = XOpenDisplay(name.c_str());
  if (display == nullptr) return false;
  XCloseDisplay(display);
  return true;
}
} // namespace

TEST(VirtualDisplay, StartsAnOpenableDisplayWhenNoneIsSet) {
  cementsph::rendering::test::forgetDisplay();
  VirtualDisplay::ensureDisplay();
  const std::string name = VirtualDisplay::displayName();
  ASSERT_FALSE(name.empty()) << "DISPLAY was not set";
  EXPECT_TRUE(canOpen(name)) << "an X client cannot open DISPLAY=" << name;
  // Repeated calls are no-ops that keep the same display.
  VirtualDisplay::ensureDisplay();
  EXPECT_EQ(VirtualDisplay::displayName(), name);
}

// The next two need a process in which ensureDisplay() has not run yet: the "threadsafe" death-test style
// re-executes the test binary for the checked statement.
TEST(VirtualDisplay, ReplacesADisplayThatCannotBeOpened) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        setenv("DISPLAY", ":4093", 1); // nothing listens there
        VirtualDisplay::ensureDisplay();
        const std::string name = VirtualDisplay::displayName();
        std::exit(name != ":4093" && canOpen(name) && VirtualDisplay::startedVirtualServer() ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "");
}

TEST(VirtualDisplay, MissingXvfbGivesOneClearLine) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const std::filesystem::path emptyBin = cementsph::rendering::test::scratchFolder();
  EXPECT_EXIT(
      {
        unsetenv("DISPLAY");
        setenv("PATH", emptyBin.c_str(), 1);
        try {
          VirtualDisplay::ensureDisplay();
        } catch (const std::runtime_error& e) {
          std::fprintf(stderr, "%s\n", e.what());
          std::exit(3);
        }
        std::exit(0);
      },
      ::testing::ExitedWithCode(3), "'xvfb' package.*scripts/install-deps.sh");
}
