// Files in and out (app/files.hpp): a table is the program's own copy,
// whatever happens to its file; an output replaces its file only when
// complete; an output naming an input is refused.
#include "gabarit/app/files.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <thread>

#include "gabarit/app/args.hpp"
#include "gabarit/app/error.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir(const char* name) {
  const fs::path d = fs::temp_directory_path() / (std::string(name) + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::vector<std::byte> small_table() {
  app::Rng rng(5);
  return testing::build(testing::point_model(testing::random_points(rng, 16, 6)), "-2:2:5", "-2:2:5");
}

// The file rewritten in place with other bytes of the same size, then
// truncated: the table a program opened is unchanged (it was mapped before,
// and then voted with the new file's cell numbers or died of SIGBUS).
TEST(TableFile, IsTheProgramsOwnCopyWhateverHappensToTheFile) {
  const fs::path d = temp_dir("gabarit-tablefile");
  const auto bytes = small_table();
  app::write_file((d / "t.gbt").string(), bytes);
  const app::TableFile table((d / "t.gbt").string());
  const std::uint32_t cells = table.view().cell_count(), refs = table.view().reference_count();
  {
    std::fstream f(d / "t.gbt", std::ios::in | std::ios::out | std::ios::binary);
    const std::string junk(bytes.size(), '\x5a');
    f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
  }
  fs::resize_file(d / "t.gbt", 10);
  EXPECT_EQ(table.view().cell_count(), cells);
  EXPECT_EQ(table.view().reference_count(), refs);
  EXPECT_TRUE(std::equal(bytes.begin(), bytes.end(), table.bytes().begin()));
  TableView again;
  EXPECT_EQ(TableView::open(table.bytes(), again), Status::kOk);
  fs::remove_all(d);
}

TEST(TableFile, RefusesAFileWhoseSizeIsNotTheHeadersBeforeReadingIt) {
  const fs::path d = temp_dir("gabarit-tablefile-size");
  auto bytes = small_table();
  bytes.resize(bytes.size() + 4096);  // more than the header says
  app::write_file((d / "long.gbt").string(), bytes);
  try {
    app::TableFile t((d / "long.gbt").string());
    ADD_FAILURE() << "a table longer than its header says was accepted";
  } catch (const app::Error& e) {
    EXPECT_NE(std::string(e.what()).find("not a valid table"), std::string::npos) << e.what();
  }
  fs::remove_all(d);
}

TEST(OutputFile, ReplacesItsFileOnlyWhenCommitted) {
  const fs::path d = temp_dir("gabarit-output");
  const std::string path = (d / "out.txt").string();
  app::write_file(path, std::string_view("previous\n"));
  {
    app::OutputFile out(path);
    out.write(std::string_view("half a result"));
    EXPECT_EQ(slurp(path), "previous\n") << "visible before commit";
    // Destroyed without commit (an exception unwinding, say).
  }
  EXPECT_EQ(slurp(path), "previous\n");
  try {
    app::OutputFile out(path);
    out.write(std::string_view("another"));
    throw std::runtime_error("the run failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(slurp(path), "previous\n");
  app::OutputFile out(path);
  out.write(std::string_view("complete\n"));
  out.commit();
  EXPECT_EQ(slurp(path), "complete\n");
  // No temporary left, and the mode a plain create gives (0666 less the umask).
  std::size_t entries = 0;
  for (const auto& e : fs::directory_iterator(d)) entries += e.path().filename() != "out.txt" ? 1 : 0;
  EXPECT_EQ(entries, 0u);
  const mode_t mask = ::umask(0);
  ::umask(mask);
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0666 & ~mask);
  EXPECT_THROW(app::OutputFile((d / "no-such-dir" / "x").string()), app::Error);
  fs::remove_all(d);
}

// `-o /dev/null` (or a FIFO) is written through: renaming a temporary over it
// would have replaced the device with a regular file, for every program after.
TEST(OutputFile, AnExistingFifoIsWrittenThroughAndStaysAFifo) {
  const fs::path d = temp_dir("gabarit-fifo");
  const std::string path = (d / "pipe").string();
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] { received = slurp(path); });  // opening for reading waits for the writer
  app::write_file(path, std::string_view("through the pipe\n"));
  reader.join();
  EXPECT_EQ(received, "through the pipe\n");
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO was replaced";
  std::size_t entries = 0;
  for (const auto& e : fs::directory_iterator(d)) entries += e.path().filename() != "pipe" ? 1 : 0;
  EXPECT_EQ(entries, 0u) << "a temporary was left beside the FIFO";
  EXPECT_THROW(app::OutputFile(d.string()), app::Error);  // a directory is refused
  fs::remove_all(d);
}

TEST(OutputFile, AnOutputNamingAnInputIsRefusedHoweverItIsSpelled) {
  const fs::path d = temp_dir("gabarit-same");
  const std::string input = (d / "in.y4m").string();
  app::write_file(input, std::string_view("x"));
  fs::create_hard_link(input, d / "link.y4m");
  EXPECT_THROW(app::refuse_same_file(input, "-o", {input}), app::UsageError);
  EXPECT_THROW(app::refuse_same_file((d / "." / "in.y4m").string(), "-o", {input}), app::UsageError);
  EXPECT_THROW(app::refuse_same_file((d / "link.y4m").string(), "-o", {input}), app::UsageError);
  EXPECT_NO_THROW(app::refuse_same_file((d / "other.csv").string(), "-o", {input}));  // does not exist yet
  EXPECT_THROW(app::refuse_same_file((d / "new" / ".." / "in.y4m").string(), "-o", {input}), app::UsageError);
  fs::remove_all(d);
}

}  // namespace
}  // namespace gabarit
