// scene/files.hpp: atomic replacement, checked line files, the run directory's ledger; and the
// geometry-script reader (preprocess/geo_script.hpp) on the constructs it must tell apart.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "preprocess/geo_script.hpp"
#include "preprocess/shape.hpp"
#include "scene/files.hpp"

namespace {

namespace fs = std::filesystem;
using namespace swmpm;

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / "swmpm-files" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

std::size_t entries(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

}  // namespace

TEST(Files, AtomicWriteReplacesWholeOrLeavesTheOldFile) {
  const fs::path dir = scratch("atomic");
  write(dir / "a.txt", "old\n");
  EXPECT_THROW(files::write_atomically(dir / "a.txt",
                                       [](const std::string& tmp) {
                                         write(tmp, "half");
                                         throw files::WriteError(tmp, "No space left on device");
                                       }),
               files::WriteError);
  EXPECT_EQ(read(dir / "a.txt"), "old\n");
  EXPECT_EQ(entries(dir), 1u) << "the temporary is removed";
  files::write_text_atomically(dir / "a.txt", "new\n");
  EXPECT_EQ(read(dir / "a.txt"), "new\n");
  EXPECT_EQ(entries(dir), 1u);
  struct stat st{};
  ASSERT_EQ(::stat((dir / "a.txt").c_str(), &st), 0);
  const mode_t mask = ::umask(0);
  ::umask(mask);
  EXPECT_EQ(st.st_mode & 0777, 0666 & ~mask) << "a temporary's 0600 does not stay";
  EXPECT_TRUE(files::is_temporary(".a.txt.swmpm-Ab12Cd"));
  EXPECT_FALSE(files::is_temporary("a.txt"));
  EXPECT_FALSE(files::is_temporary(".a.txt.swmpm-Ab1"));
}

TEST(Files, CheckedFileFailsLoudlyOnAFullDevice) {
  files::CheckedFile f("/dev/full");
  EXPECT_THROW(f.write("a row\n"), files::WriteError);
  try {
    f.write("next\n");
    FAIL() << "every later write fails too";
  } catch (const files::WriteError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/full: cannot write the file: No space left on device"), std::string::npos)
        << e.what();
  }
}

TEST(Files, LedgerGuardsTheUsersFiles) {
  const fs::path dir = scratch("ledger");
  write(dir / "scene.json", "{\"mine\": true}\n");
  files::RunDirectory run(dir);
  EXPECT_FALSE(run.holds_a_run());
  EXPECT_THROW(run.claim("scene.json"), files::RunDirectoryError);
  EXPECT_EQ(run.foreign(files::swmpm_files_in(dir)), std::vector<std::string>{"scene.json"});
  run.write_text("output/results.pvd", "x\n");
  write(dir / "output" / "notes.txt", "mine\n");
  EXPECT_TRUE(run.holds_a_run());
  // A ledger line that points outside the folder is not believed.
  std::ofstream(dir / ".swmpm-files", std::ios::app) << "../outside.txt\n/etc/passwd\n";
  write(dir.parent_path() / "outside.txt", "elsewhere\n");
  files::RunDirectory again(dir);
  EXPECT_TRUE(again.owns("output/results.pvd"));
  EXPECT_FALSE(again.owns("../outside.txt"));
  again.remove_owned([](const std::string&) { return true; });
  EXPECT_FALSE(fs::exists(dir / "output" / "results.pvd"));
  EXPECT_EQ(read(dir / "output" / "notes.txt"), "mine\n");
  EXPECT_EQ(read(dir / "scene.json"), "{\"mine\": true}\n");
  EXPECT_EQ(read(dir.parent_path() / "outside.txt"), "elsewhere\n");
  EXPECT_FALSE(fs::exists(dir / ".swmpm-files")) << "nothing of swmpm's is left, nor its ledger";
}

TEST(GeoScript, TellsCommandsFromWordsInStringsAndComments) {
  const fs::path dir = scratch("geo");
  const pre::GeoScriptRoots roots{{dir}};
  auto refusal = [&](const std::string& text) -> std::string {
    write(dir / "g.geo", text);
    try {
      pre::check_geo_script(dir / "g.geo", roots);
    } catch (const pre::GeometryError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(refusal("// SystemCall \"rm -rf /\";\n/* Exit; */\nPrintf(\"Save %g\", 1);\nx = 1; Mesh.Algorithm = 6;\n"), "");
  EXPECT_EQ(refusal("If (2 > 1) Printf(\"a\"); EndIf\nMesh.MeshSizeMax = 0.1;\nSystemCallx = 2;\n"), "");
  EXPECT_NE(refusal("a = 1;\n\n  SystemCall \"id\";\n").find("g.geo:3: `SystemCall` runs a shell command"),
            std::string::npos);
  EXPECT_NE(refusal("Printf(\"%g\", Sin(1)) >\n\"out.txt\";").find("`Printf(...) >` writes to a file"), std::string::npos);
  EXPECT_NE(refusal("View[0].Visible = 0;").find("`View` acts on post-processing views"), std::string::npos);
  write(dir / "inner.geo", "SystemCall \"id\";\n");
  EXPECT_NE(refusal("Include \"inner.geo\";").find("inner.geo:1: `SystemCall`"), std::string::npos)
      << "an included file is read with the same rules";
  fs::create_directories(dir / "sub");
  fs::create_symlink("/etc", dir / "sub" / "etc");
  EXPECT_NE(refusal("Include \"sub/etc/passwd\";").find("reads a file outside the allowed folders"), std::string::npos)
      << "a symlink out of the folder is followed before the check";
  write(dir / "self.geo", "Include \"self.geo\";\n");
  EXPECT_EQ(refusal("Include \"self.geo\";"), "") << "an Include cycle ends";
}

TEST(GeoScript, PrivateTempFileIsUnpredictableAndGone) {
  fs::path dir, file;
  {
    const pre::PrivateTempFile t("p.geo", "s = 1;\n");
    file = t.path();
    dir = file.parent_path();
    EXPECT_EQ(read(file), "s = 1;\n");
    struct stat st{};
    ASSERT_EQ(::stat(dir.c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 0777, 0700u);
    EXPECT_EQ(dir.filename().string().rfind("swmpm-", 0), 0u);
    const pre::PrivateTempFile other("p.geo", "");
    EXPECT_NE(other.path(), file);
  }
  EXPECT_FALSE(fs::exists(dir));
}
