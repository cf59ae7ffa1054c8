// libFuzzer target: bytes -> the scene parser every subcommand reads a scene file with (loadSceneFile: the
// whole file read, NUL bytes refused, nlohmann::json, sceneFromJson's keys, validate()).
// loadSceneFile zero-fills a 16 MiB buffer per call (40 runs/s under ASan), so each input goes first through
// the same steps in memory (json::parse; sceneFromJson for a JSON object), then through loadSceneFile itself
// when that accepts it, and for one refused object in 8 (loadSceneFile only wraps the refusal then).
// A refusal (std::exception, one line, starting with the path for loadSceneFile) is the accepted outcome; a
// crash, a hang, undefined behaviour or a leak is a finding. Two more oracles: the file and the in-memory
// parse agree (both accept or both refuse), and a scene that loads survives its own round trip (toJson,
// then sceneFromJson, accepts it).
#include "FuzzCommon.h"
#include "cementsph/scene/SceneConfig.h"

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <functional>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace cementsph::scene;
  const std::string text(reinterpret_cast<const char*>(data), size);
  if (text.find('\0') != std::string::npos) return 0; // refused by loadSceneFile before parsing (SceneConfigTest)
  const nlohmann::json parsed = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (parsed.is_discarded() || !parsed.is_object()) return 0; // refused by loadSceneFile (not JSON, not an object)
  bool acceptedInMemory = true;
  try {
    (void)sceneFromJson(parsed);
  } catch (const std::exception& e) {
    cementsph::fuzz::requireReadableRefusal(e, "", "scene_json");
    acceptedInMemory = false;
  }
  // A refused object goes through the file too for one input in 8 (chosen by its bytes, so a run is
  // reproducible): loadSceneFile only wraps the refusal then.
  if (!acceptedInMemory && std::hash<std::string>{}(text) % 8 != 0) return 0;
  const std::string path = cementsph::fuzz::writeFile("scene.json", data, size);
  try {
    const SceneConfig s = loadSceneFile(path);
    const nlohmann::json j = toJson(s);
    try {
      (void)sceneFromJson(j);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "scene_json: a scene that loaded is refused after toJson: %s\n%s\n", e.what(),
                   j.dump().c_str());
      std::abort();
    }
    if (!acceptedInMemory) {
      std::fprintf(stderr, "scene_json: loadSceneFile accepts what sceneFromJson refuses\n");
      std::abort();
    }
  } catch (const std::exception& e) {
    cementsph::fuzz::requireReadableRefusal(e, path, "scene_json");
    // One refusal only the file can make: a key twice in one object (json::parse keeps the last, so the parsed
    // object above no longer shows it; SceneConfigTest holds the cases).
    const bool duplicateKey = std::string(e.what()).find("' appears twice in one object") != std::string::npos;
    if (acceptedInMemory && !duplicateKey) {
      std::fprintf(stderr, "scene_json: loadSceneFile refuses what sceneFromJson accepts: %s\n", e.what());
      std::abort();
    }
  }
  return 0;
}
