// apps/cli_files.h check_outputs: every output against every input and every
// other output by file identity, and never over a file of another kind.
#include "apps/cli_files.h"

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "tests/temp_dir.h"
#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

// The InputError check_outputs throws ("" if none).
std::string refusal(const std::vector<std::string>& inputs, const std::vector<OutputFile>& outputs) {
  try {
    check_outputs(inputs, outputs);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

const std::string kPng = std::string("\x89PNG\r\n\x1a\n", 8) + "rest";

TEST(CheckOutputs, AnInputUnderAnyNameIsRefused) {
  const TempDir dir("glasspiv_cli_files_inputs");
  const std::string photo = dir.file("photo.png");
  write_file_atomically(photo, kPng);
  ASSERT_EQ(::link(photo.c_str(), dir.file("hard.png").c_str()), 0);
  ASSERT_EQ(::symlink("photo.png", dir.file("soft.png").c_str()), 0);
  ASSERT_EQ(::chdir(dir.file("").c_str()), 0);
  for (const std::string& name : {photo, dir.file("hard.png"), dir.file("./photo.png"), dir.file("x/../photo.png")})
    EXPECT_NE(refusal({photo}, {{name, "-o"}}).find("never overwrites its inputs"), std::string::npos) << name;
  EXPECT_NE(refusal({"photo.png"}, {{"./photo.png", "-o"}}).find("never overwrites"), std::string::npos);
  // A symbolic link output names the input (and is not a regular file either).
  EXPECT_NE(refusal({photo}, {{dir.file("soft.png"), "-o"}}), "");
}

TEST(CheckOutputs, TwoOutputsThatAreOneFileAreRefusedEvenIfNew) {
  const TempDir dir("glasspiv_cli_files_twice");
  ASSERT_EQ(::chdir(dir.file("").c_str()), 0);
  const std::string r = refusal({}, {{"cj.png", "-o", OutputKind::image}, {"./cj_edges.png", "-o", OutputKind::image},
                                     {"cj_edges.png", "--json", OutputKind::json}});
  EXPECT_NE(r.find("--json"), std::string::npos) << r;
  EXPECT_NE(r.find("same output"), std::string::npos) << r;
}

TEST(CheckOutputs, AnExistingFileOfAnotherKindIsNeverReplaced) {
  const TempDir dir("glasspiv_cli_files_kinds");
  const std::string tif = dir.file("frame.tif"), json = dir.file("old.json"), text = dir.file("notes.yaml");
  write_file_atomically(tif, std::string("II*\0", 4) + "tiff data");
  write_file_atomically(json, "{\"a\": 1}\n");
  write_file_atomically(text, "a: 1\n");
  const std::string map = refusal({}, {{tif, "--map", OutputKind::transport_map}});
  EXPECT_NE(map.find("--map"), std::string::npos) << map;
  EXPECT_NE(map.find("is not a transport map"), std::string::npos) << map;
  EXPECT_NE(refusal({}, {{tif, "--json", OutputKind::json}}).find("is not a JSON file"), std::string::npos);
  EXPECT_NE(refusal({}, {{tif, "-o", OutputKind::text}}).find("is not a text file"), std::string::npos);
  EXPECT_NE(refusal({}, {{json, "-o", OutputKind::image}}).find("is not an image"), std::string::npos);
  // The same kind, an empty file and a new name are replaced or created.
  EXPECT_EQ(refusal({}, {{tif, "-o", OutputKind::image}}), "");
  EXPECT_EQ(refusal({}, {{json, "--json", OutputKind::json}}), "");
  EXPECT_EQ(refusal({}, {{text, "-o"}}), "");
  write_file_atomically(dir.file("empty.tmap"), "");
  EXPECT_EQ(refusal({}, {{dir.file("empty.tmap"), "--map", OutputKind::transport_map}}), "");
  EXPECT_EQ(refusal({}, {{dir.file("new.tmap"), "--map", OutputKind::transport_map}}), "");
  // By extension when no kind is given: a .png output over a YAML text.
  write_file_atomically(dir.file("wrong.png"), "a: 1\n");
  EXPECT_NE(refusal({}, {{dir.file("wrong.png"), "-o"}}).find("is not an image"), std::string::npos);
  // A folder output must be a folder.
  EXPECT_NE(refusal({}, {{text, "-o", OutputKind::folder}}).find("is not a folder"), std::string::npos);
  EXPECT_EQ(refusal({}, {{dir.file(""), "-o", OutputKind::folder}}), "");
}

TEST(CheckOutputs, ANameTooLongIsRefusedInWords) {
  const TempDir dir("glasspiv_cli_files_long");
  const std::string folder = dir.file(std::string(300, 'a'));
  const std::string r = refusal({}, {{folder + "/x.tif", "-o"}});
  EXPECT_NE(r.find("-o"), std::string::npos) << r;
  EXPECT_NE(r.find("over the file system's limit of 255 bytes"), std::string::npos) << r;
  EXPECT_THROW(check_output_folder(folder, "-o"), InputError);
  EXPECT_THROW(make_output_folder(folder, "-o"), InputError);
}

}  // namespace
}  // namespace glasspiv
