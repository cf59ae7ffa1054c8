// A scene file that is not JSON (issue 21, session 6): the one line that refuses it names the file, the line and
// column where the JSON breaks, the key whose value (or name) it is in, and why, in the parser's words without
// its "[json.exception...]" tag; a NUL byte is placed the same way. The oracle is each file's own text: where the
// test put the fault (its line, column and key, counted by hand).
#include "cementsph/scene/SceneConfig.h"
#include "cementsph/scene/SceneSettings.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace {

using cementsph::scene::loadSceneFile;

std::string errorOfSceneText(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::temp_directory_path() / "cementsph-scene-file-errors";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path, std::ios::binary) << text;
  try {
    (void)loadSceneFile(path);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "accepted";
}

void expectOneLineNaming(const std::string& error, const std::vector<std::string>& parts) {
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  EXPECT_LT(error.size(), 400u) << error;
  EXPECT_EQ(error.find("json.exception"), std::string::npos) << error;
  for (const std::string& p : parts) EXPECT_NE(error.find(p), std::string::npos) << "'" << p << "' not in: " << error;
}

} // namespace

// NaN and Infinity are not JSON: the literal's line and column (the 'N' of NaN is at line 3, column 21), and the key.
TEST(SceneFileErrors, ANonJsonLiteralNamesItsLineColumnAndKey) {
  const std::string text = "{\n  \"tip_mm\": [1, 2, 3],\n  \"viscosity_pa_s\": NaN\n}\n";
  expectOneLineNaming(errorOfSceneText("nan.json", text),
                      {"nan.json: line 3, column", "in key 'viscosity_pa_s'", "invalid literal", "not valid JSON"});
}

// A number past the double range: the parser's "number overflow" and the key, the 400-digit number itself cut to
// 40 characters (the line stays short).
TEST(SceneFileErrors, AnOverflowingNumberNamesItsKeyAndStaysShort) {
  const std::string text = "{\"tip_mm\": [1, 2, 3], \"volume_ml\": 1" + std::string(400, '0') + "}";
  expectOneLineNaming(errorOfSceneText("huge.json", text), {"huge.json: line 1, column", "in key 'volume_ml'", "overflow"});
}

// A control character inside a string, and text after the object: the line and column, and for the string its key.
TEST(SceneFileErrors, AControlCharacterOrTrailingTextIsPlaced) {
  const std::string control = "{\"tip_mm\": [1, 2, 3],\n\"scene_preset\": \"ab\x01" "c\"}";
  expectOneLineNaming(errorOfSceneText("control.json", control), {"control.json: line 2, column", "in key 'scene_preset'"});
  const std::string trailing = "{\"tip_mm\": [1, 2, 3]}\n garbage";
  expectOneLineNaming(errorOfSceneText("trailing.json", trailing), {"trailing.json: line 2, column ", "not valid JSON"});
}

// A NUL byte inside a string value: its byte offset, line, column and key (offset 40 is line 2, column 19).
TEST(SceneFileErrors, ANulByteIsPlacedByLineColumnAndKey) {
  const std::string text = std::string("{\"tip_mm\": [1, 2, 3],\n\"scene_preset\": \"a") + '\0' + "b\"}";
  expectOneLineNaming(errorOfSceneText("nul.json", text),
                      {"nul.json: line 2, column 19", "in key 'scene_preset'", "(byte 40)", "NUL byte"});
}

// Range refusals share one wording (SceneConfig.cpp's requireAtLeast/requireAtMost): the key, the value and the limit
// in the key's unit, why, and what to do.
TEST(SceneFileErrors, RangeRefusalsNameKeyValueLimitAndUnit) {
  expectOneLineNaming(errorOfSceneText("big-volume.json", R"({"tip_mm": [1, 2, 3], "volume_ml": 2000})"),
                      {"key 'volume_ml' is too large: 2000 ml is above 1000 ml (", "give the volume in ml"});
  expectOneLineNaming(errorOfSceneText("thin.json", R"({"tip_mm": [1, 2, 3], "viscosity_pa_s": 1e-05})"),
                      {"key 'viscosity_pa_s' is too small: 1e-05 Pa.s is below 0.0001 Pa.s (", "give the viscosity in Pa.s"});
}

// An empty scene file (or white space only) says so, with what a scene looks like.
TEST(SceneFileErrors, AnEmptyFileSaysSo) {
  expectOneLineNaming(errorOfSceneText("empty.json", ""), {"empty.json: the scene file is empty", "tip_mm"});
  expectOneLineNaming(errorOfSceneText("blank.json", " \n\t\n"), {"blank.json: the scene file is empty"});
}
