// The study's CSV and Markdown (StudyReport.h): one row per run, the documented columns, absent figures
// as empty fields / "n/a" and never NaN, failed runs kept with their reason.
#include "StudyRowsForTests.h"

#include "cementsph/study/StudyReport.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

using namespace cementsph::study;
using namespace cementsph::study::testing;

namespace {

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

// Fields of a CSV line (no quoted commas in these tests).
std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  for (std::string f; std::getline(ss, f, ',');) out.push_back(f);
  if (!line.empty() && line.back() == ',') out.push_back("");
  return out;
}

std::size_t column(const std::string& header, const std::string& name) {
  const auto names = fields(header);
  const auto it = std::find(names.begin(), names.end(), name);
  EXPECT_NE(it, names.end()) << name;
  return static_cast<std::size_t>(it - names.begin());
}

// Table rows of one Markdown section: lines starting with "| " after the header's separator line.
std::size_t tableRows(const std::string& md, const std::string& section) {
  const auto all = lines(md);
  auto it = std::find(all.begin(), all.end(), section);
  if (it == all.end()) return 0;
  it = std::find_if(it, all.end(), [](const std::string& l) { return l.rfind("|---", 0) == 0; });
  std::size_t n = 0;
  for (++it; it != all.end() && it->rfind("| ", 0) == 0; ++it) ++n;
  return n;
}

} // namespace

TEST(StudyReport, CsvHasOneRowPerRunWithTheDocumentedColumns) {
  const auto rows = paperLikeRows();
  const auto csv = lines(sizeStudyCsv(rows));
  ASSERT_EQ(csv.size(), rows.size() + 1);
  const std::string& header = csv[0];
  for (const char* name : {"run", "integrator", "particle_radius_mm", "reference", "status", "wall_time_s",
                           "real_time_factor", "steps", "fluid_particles", "expected_fluid_particles",
                           "fixed_particles", "surface_error_mm", "dice", "spreading_difference_mm", "failure"})
    column(header, name);
  const std::size_t n = fields(header).size();
  for (std::size_t i = 1; i < csv.size(); ++i) EXPECT_EQ(fields(csv[i]).size(), n) << csv[i];
  // First row: the reference, exactly as given.
  const auto first = fields(csv[1]);
  EXPECT_EQ(first[column(header, "integrator")], "central-difference");
  EXPECT_EQ(first[column(header, "particle_radius_mm")], "0.45");
  EXPECT_EQ(first[column(header, "reference")], "1");
  EXPECT_EQ(first[column(header, "surface_error_mm")], "0");
  EXPECT_EQ(first[column(header, "dice")], "1");
  EXPECT_EQ(first[column(header, "wall_time_s")], "90");
  // Numbers read back exactly.
  EXPECT_EQ(std::stod(fields(csv[2])[column(header, "real_time_factor")]), rows[1].realTimeFactor);
}

TEST(StudyReport, AbsentFiguresAreEmptyAndFailedRunsKeepTheirReason) {
  auto rows = paperLikeRows();
  rows[2].failure = "simulation unstable at step 7 (\"runaway\")";
  rows[3].cementFound = false;
  rows[3].errors = {};
  rows[3].errors.dice = 0.0;
  const std::string text = sizeStudyCsv(rows);
  const auto csv = lines(text);
  const std::string& header = csv[0];
  const auto failed = fields(csv[3]);
  EXPECT_EQ(failed[column(header, "status")], "failed");
  EXPECT_EQ(failed[column(header, "wall_time_s")], "");
  EXPECT_NE(csv[3].find("\"simulation unstable at step 7 (\"\"runaway\"\")\""), std::string::npos) << csv[3];
  const auto noCement = fields(csv[4]);
  EXPECT_EQ(noCement[column(header, "surface_error_mm")], "");
  EXPECT_EQ(noCement[column(header, "cement_spreading_distance_mm")], "");
  EXPECT_EQ(noCement[column(header, "dice")], "0");
  for (const char* bad : {"nan", "inf", "NaN", "Inf"}) EXPECT_EQ(text.find(bad), std::string::npos) << bad;

  const std::string md = studyMarkdown(rows, {}, {"preamble line"});
  EXPECT_NE(md.find("failed (1)"), std::string::npos) << md;
  EXPECT_NE(md.find("(1) overdamped_r0.75mm: simulation unstable"), std::string::npos) << md;
  EXPECT_NE(md.find("| n/a |"), std::string::npos) << md;
  EXPECT_EQ(md.find("nan"), std::string::npos) << md;
}

TEST(StudyReport, MarkdownHasOneTableRowPerRun) {
  const auto rows = paperLikeRows();
  const std::vector<StudyRow> sweep{viscosityRow(50, 6.2), viscosityRow(100, 5.8), viscosityRow(400, 4.9)};
  const std::string md = studyMarkdown(rows, sweep, {"CT `x`.", "Reference: y."});
  EXPECT_EQ(tableRows(md, "## Particle size (paper Fig. 6)"), rows.size()) << md;
  EXPECT_EQ(tableRows(md, "## Spreading against viscosity (paper Fig. 8)"), sweep.size()) << md;
  EXPECT_NE(md.find("| central-difference (reference) | 0.45 |"), std::string::npos) << md;
  EXPECT_NE(md.find("Reference: y."), std::string::npos);
  // Without a sweep there is no sweep section, and the other way round.
  EXPECT_EQ(studyMarkdown(rows, {}, {}).find("Fig. 8"), std::string::npos);
  EXPECT_EQ(studyMarkdown({}, sweep, {}).find("Fig. 6"), std::string::npos);
}

TEST(StudyReport, ViscosityCsvHasOneRowPerViscosity) {
  const std::vector<StudyRow> sweep{viscosityRow(50, 6.2), viscosityRow(400, 4.9)};
  const auto csv = lines(viscosityCsv(sweep));
  ASSERT_EQ(csv.size(), 3u);
  const std::string& header = csv[0];
  EXPECT_EQ(header.rfind("viscosity_pa_s,particle_radius_mm,integrator,status,particle_spreading_distance_mm,"
                         "cement_spreading_distance_mm,",
                         0),
            0u)
      << header;
  EXPECT_EQ(fields(csv[2])[column(header, "viscosity_pa_s")], "400");
  EXPECT_EQ(fields(csv[2])[column(header, "particle_spreading_distance_mm")], "4.9");
}

TEST(StudyReport, RadiusLabelHasTwoDecimals) {
  EXPECT_EQ(radiusLabel(1.0), "1.00");
  EXPECT_EQ(radiusLabel(0.5), "0.50");
  EXPECT_EQ(radiusLabel(0.57), "0.57");
}
