// SimulatedRun as bytes, for the trip from a worker rank to rank 0 (StudyRunner.h):
//   "CSPHRUN1" | u64 length of the JSON | JSON {"failure", "metrics"} | u8 has image |
//   u64 size[3] | f64 origin[3] | f64 spacing[3] | f64 direction[9] (row-major) | f32 voxels, x fastest.
// Both ends are the same program on machines of one kind (a cluster's nodes), so numbers go in the
// machine's own byte order.
#include "cementsph/study/StudyRunner.h"

#include <cstdint>
#include <cstring>
#include <stdexcept>

namespace cementsph::study {

namespace {
constexpr char kMagic[8] = {'C', 'S', 'P', 'H', 'R', 'U', 'N', '1'};

template <typename T> void put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

class Reader {
public:
  explicit Reader(const std::string& bytes) : bytes_(bytes) {}
  template <typename T> T get() {
    T value;
    std::memcpy(&value, take(sizeof(T)), sizeof(T));
    return value;
  }
  const char* take(std::size_t n) {
    if (n > bytes_.size() - at_) throw std::runtime_error("a study run's bytes end early (not an encoded run)");
    const char* p = bytes_.data() + at_;
    at_ += n;
    return p;
  }

private:
  const std::string& bytes_;
  std::size_t at_ = 0;
};
} // namespace

std::string encodeSimulatedRun(const SimulatedRun& run) {
  std::string out(kMagic, sizeof kMagic);
  const std::string json = nlohmann::json{{"failure", run.failure}, {"metrics", run.metrics}}.dump();
  put(out, std::uint64_t(json.size()));
  out += json;
  const imaging::ImageType* image = run.simulatedCt.GetPointer();
  put(out, std::uint8_t(image ? 1 : 0));
  if (!image) return out;
  const auto size = image->GetLargestPossibleRegion().GetSize();
  for (unsigned a = 0; a < 3; ++a) put(out, std::uint64_t(size[a]));
  for (unsigned a = 0; a < 3; ++a) put(out, double(image->GetOrigin()[a]));
  for (unsigned a = 0; a < 3; ++a) put(out, double(image->GetSpacing()[a]));
  for (unsigned r = 0; r < 3; ++r)
    for (unsigned c = 0; c < 3; ++c) put(out, double(image->GetDirection()(r, c)));
  const std::size_t voxels = std::size_t(size[0]) * size[1] * size[2];
  out.append(reinterpret_cast<const char*>(image->GetBufferPointer()), voxels * sizeof(float));
  return out;
}

SimulatedRun decodeSimulatedRun(const std::string& bytes) {
  Reader in(bytes);
  if (std::memcmp(in.take(sizeof kMagic), kMagic, sizeof kMagic) != 0)
    throw std::runtime_error("a study run's bytes do not start with its mark (not an encoded run)");
  const auto jsonLength = in.get<std::uint64_t>();
  const nlohmann::json json = nlohmann::json::parse(std::string(in.take(std::size_t(jsonLength)), std::size_t(jsonLength)));
  SimulatedRun run;
  run.failure = json.at("failure").get<std::string>();
  run.metrics = json.at("metrics");
  if (in.get<std::uint8_t>() == 0) return run;
  imaging::ImageType::SizeType size;
  for (unsigned a = 0; a < 3; ++a) size[a] = in.get<std::uint64_t>();
  imaging::ImageType::PointType origin;
  imaging::ImageType::SpacingType spacing;
  imaging::ImageType::DirectionType direction;
  for (unsigned a = 0; a < 3; ++a) origin[a] = in.get<double>();
  for (unsigned a = 0; a < 3; ++a) spacing[a] = in.get<double>();
  for (unsigned r = 0; r < 3; ++r)
    for (unsigned c = 0; c < 3; ++c) direction(r, c) = in.get<double>();
  auto image = imaging::ImageType::New();
  imaging::ImageType::RegionType region;
  region.SetSize(size);
  image->SetRegions(region);
  image->SetOrigin(origin);
  image->SetSpacing(spacing);
  image->SetDirection(direction);
  image->Allocate();
  const std::size_t voxels = std::size_t(size[0]) * size[1] * size[2];
  std::memcpy(image->GetBufferPointer(), in.take(voxels * sizeof(float)), voxels * sizeof(float));
  run.simulatedCt = image;
  return run;
}

} // namespace cementsph::study
