// output.compression: the VTU frames' binary data as zlib (level 1, the default), lz4 or none.
// Compression is lossless, so every array of every frame must read back bitwise equal whichever
// compressor wrote it; the file must name the compressor a reader needs; and run.json must count
// the time spent writing frames (frame_seconds, part of loop_seconds).
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "support/run_helpers.hpp"

namespace {

using nlohmann::json;
using swmpm::scene::PointCloud;
using namespace swmpm::testing;

json column(const std::string& compression) {
  json s = load_json(SWMPM_SOURCE_DIR "/examples/elastic-column/scene.json");
  s["time"]["end"] = 0.2;
  s["output"]["interval"] = 0.05;
  if (!compression.empty()) s["output"]["compression"] = compression;
  return s;
}

/// Bitwise comparison of two clouds: positions and every array (names, components, values).
void expect_bitwise_equal(const PointCloud& a, const PointCloud& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  ASSERT_EQ(a.arrays.size(), b.arrays.size()) << what;
  EXPECT_EQ(std::memcmp(a.points.data(), b.points.data(), a.size() * sizeof(a.points[0])), 0) << what;
  for (std::size_t k = 0; k < a.arrays.size(); ++k) {
    const auto& x = a.arrays[k];
    const auto& y = b.arrays[k];
    EXPECT_EQ(x.name, y.name) << what;
    EXPECT_EQ(x.components, y.components) << what << " " << x.name;
    ASSERT_EQ(x.values.size(), y.values.size()) << what << " " << x.name;
    EXPECT_EQ(std::memcmp(x.values.data(), y.values.data(), x.values.size() * sizeof(double)), 0)
        << what << " " << x.name;
  }
}

TEST(OutputCompression, EveryCompressorWritesTheSameFramesAndNamesItself) {
  const std::string zlib_run = run_scene(column(""), "compression-default");
  const auto frames = swmpm::scene::read_pvd(zlib_run + "/output/results.pvd");
  ASSERT_EQ(frames.size(), 5u);  // t = 0, 0.05, ..., 0.2
  const json rj = load_json(zlib_run + "/run.json");
  EXPECT_GT(rj["frame_seconds"].get<double>(), 0.0);
  EXPECT_LT(rj["frame_seconds"].get<double>(), rj["loop_seconds"].get<double>());

  const struct {
    std::string name, header;
  } cases[] = {{"zlib", "compressor=\"vtkZLibDataCompressor\""},
               {"lz4", "compressor=\"vtkLZ4DataCompressor\""},
               {"none", ""}};
  for (const auto& c : cases) {
    const std::string run = run_scene(column(c.name), "compression-" + c.name);
    for (const auto& f : frames) {
      const std::string file = "/output/" + f.file;
      const std::string text = read_text(run + file);
      const std::string head = text.substr(0, text.find("<AppendedData"));
      if (c.header.empty()) EXPECT_EQ(head.find("compressor="), std::string::npos) << c.name << file;
      else EXPECT_NE(head.find(c.header), std::string::npos) << c.name << file;
      expect_bitwise_equal(swmpm::scene::read_vtu(zlib_run + file), swmpm::scene::read_vtu(run + file),
                           c.name + file);
    }
  }
}

}  // namespace
