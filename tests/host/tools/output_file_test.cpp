// tools::OutputFile, OutputPath, InputFiles and finish_stdout (output_file.h): a failed or
// interrupted write leaves the old file and no temporary; devices are written in place and
// never removed; an output that is an input is recognised by identity.
#include "seqslam_tools/output_file.h"

#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "seqslam/hal/file_block_device.h"
#include "seqslam/hal/host_file.h"
#include "seqslam_tools/image_io.h"
#include "test_util.h"

namespace seqslam::tools {
namespace {

namespace fs = std::filesystem;
using test::read_file;
using test::TempDir;
using test::to_string;
using test::write_file;

// The names in `dir`, hidden ones (the temporaries) included.
std::vector<std::string> names_in(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir))
    names.push_back(entry.path().filename().string());
  return names;
}

bool exists(const std::string& path) {
  struct stat st;
  return lstat(path.c_str(), &st) == 0;
}

TEST(OutputFile, ReplacesTheTargetOnlyOnCommit) {
  TempDir dir;
  const std::string path = dir.file("out.csv");
  write_file(path, "old\n");
  OutputFile out;
  ASSERT_EQ(out.open(path), "");
  EXPECT_FALSE(out.in_place());
  EXPECT_TRUE(out.print("%s,%d\n", "new", 1));
  EXPECT_TRUE(out.flush());
  EXPECT_EQ(to_string(read_file(path)), "old\n");  // the target is untouched until commit
  EXPECT_EQ(names_in(dir.path()).size(), 2u);      // target and temporary
  EXPECT_EQ(out.commit(), "");
  EXPECT_EQ(to_string(read_file(path)), "new,1\n");
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"out.csv"});
}

TEST(OutputFile, NotCommittedLeavesTheOldFileAndNoTemporary) {
  TempDir dir;
  const std::string path = dir.file("out.csv");
  write_file(path, "old\n");
  {
    OutputFile out;
    ASSERT_EQ(out.open(path), "");
    out.write(std::string_view("partial"));
  }
  EXPECT_EQ(to_string(read_file(path)), "old\n");
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"out.csv"});
  {
    OutputFile out;
    ASSERT_EQ(out.open(dir.file("new.csv")), "");
    out.discard();
  }
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"out.csv"});
}

TEST(OutputFile, KeepsTheModeOfTheFileItReplaces) {
  TempDir dir;
  const std::string path = dir.file("out.txt");
  write_file(path, "old");
  ASSERT_EQ(chmod(path.c_str(), 0640), 0);
  ASSERT_EQ(write_output(path, "new"), "");
  struct stat st;
  ASSERT_EQ(stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0640u);
}

TEST(OutputFile, AReadOnlyFileIsNotReplaced) {
  if (geteuid() == 0) GTEST_SKIP() << "root may write any file";
  TempDir dir;
  const std::string path = dir.file("locked.txt");
  write_file(path, "old");
  ASSERT_EQ(chmod(path.c_str(), 0444), 0);
  EXPECT_EQ(write_output(path, "new"), path + ": cannot open for writing: Permission denied");
  EXPECT_EQ(to_string(read_file(path)), "old");
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"locked.txt"});
}

TEST(OutputFile, WritesThroughASymbolicLinkAndKeepsIt) {
  TempDir dir;
  write_file(dir.file("real.txt"), "old");
  fs::create_symlink("real.txt", dir.file("link.txt"));
  ASSERT_EQ(write_output(dir.file("link.txt"), "new"), "");
  EXPECT_TRUE(fs::is_symlink(dir.file("link.txt")));
  EXPECT_EQ(to_string(read_file(dir.file("real.txt"))), "new");
}

TEST(OutputFile, AFullDeviceFailsWithTheReasonAndIsNotRemoved) {
  if (!exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  OutputFile out;
  ASSERT_EQ(out.open("/dev/full"), "");
  EXPECT_TRUE(out.in_place());
  out.write(std::string_view("a few bytes, buffered until the flush\n"));
  const std::string error = out.commit();
  EXPECT_EQ(error, "/dev/full: write failed: No space left on device");
  EXPECT_TRUE(exists("/dev/full"));
  // A write larger than the buffer fails at once.
  ASSERT_EQ(out.open("/dev/full"), "");
  const std::string big(1 << 20, 'x');
  EXPECT_FALSE(out.write(big));
  EXPECT_TRUE(out.failed());
  EXPECT_EQ(out.commit(), "/dev/full: write failed: No space left on device");
  // The image writers (write_file_bytes, as the report and map writers) report it too.
  GrayImage image;
  image.width = 64;
  image.height = 64;
  image.pixels.assign(64 * 64, 128);
  std::string message;
  EXPECT_FALSE(save_pgm("/dev/full", image, &message));
  EXPECT_EQ(message, "/dev/full: write failed: No space left on device");
}

TEST(OutputFile, AppendModeAppendsInPlace) {
  TempDir dir;
  const std::string path = dir.file("rows.csv");
  write_file(path, "header\nrow 1\n");
  OutputFile out;
  ASSERT_EQ(out.open(path, OutputFile::Mode::kAppend), "");
  EXPECT_TRUE(out.in_place());
  EXPECT_TRUE(out.print("row %d\n", 2));
  EXPECT_TRUE(out.flush());
  EXPECT_EQ(to_string(read_file(path)), "header\nrow 1\nrow 2\n");  // flushed: kept as written
  EXPECT_EQ(out.commit(), "");
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"rows.csv"});
}

TEST(OutputFile, RefusesADirectoryAndNamesAMissingOne) {
  TempDir dir;
  OutputFile out;
  EXPECT_EQ(out.open(dir.path()), dir.path() + ": is a directory, not a file");
  EXPECT_EQ(out.open(dir.file("no/such.csv")),
            dir.file("no/such.csv") + ": cannot create: No such file or directory");
  EXPECT_EQ(out.open(""), "(empty path): no output file name given");
}

TEST(OutputPath, HandsOutATemporaryRenamedOnCommit) {
  TempDir dir;
  const std::string path = dir.file("card.img");
  write_file(path, "old");
  OutputPath out;
  ASSERT_EQ(out.open(path), "");
  EXPECT_FALSE(out.in_place());
  EXPECT_NE(out.write_path(), path);
  EXPECT_EQ(fs::path(out.write_path()).parent_path(), fs::path(path).parent_path());
  write_file(out.write_path(), "new");
  EXPECT_EQ(out.shown(out.write_path() + ": cannot write"), path + ": cannot write");
  EXPECT_EQ(to_string(read_file(path)), "old");
  EXPECT_EQ(out.commit(), "");
  EXPECT_EQ(to_string(read_file(path)), "new");
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"card.img"});

  OutputPath dropped;
  ASSERT_EQ(dropped.open(path), "");
  write_file(dropped.write_path(), "half");
  dropped.discard();
  EXPECT_EQ(to_string(read_file(path)), "new");
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"card.img"});
}

TEST(OutputPath, UsesADeviceInPlaceAndRefusesAFifo) {
  TempDir dir;
  if (exists("/dev/null")) {
    OutputPath device;
    ASSERT_EQ(device.open("/dev/null"), "");
    EXPECT_TRUE(device.in_place());
    EXPECT_EQ(device.write_path(), "/dev/null");
    EXPECT_EQ(device.commit(), "");
    EXPECT_TRUE(exists("/dev/null"));
  }
  const std::string fifo = dir.file("pipe");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  OutputPath out;
  EXPECT_NE(out.open(fifo).find(fifo + ": is a FIFO or socket"), std::string::npos);
  struct stat st;
  ASSERT_EQ(stat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
}

TEST(InputFiles, RecognisesAnInputByIdentity) {
  TempDir dir;
  write_file(dir.file("a.img"), "a");
  write_file(dir.file("b.img"), "b");
  ASSERT_EQ(link(dir.file("a.img").c_str(), dir.file("hard.img").c_str()), 0);
  fs::create_symlink("a.img", dir.file("soft.img"));
  InputFiles inputs;
  inputs.add(dir.file("a.img"));
  inputs.add(dir.file("missing.img"));  // ignored
  inputs.add("-");                      // ignored
  EXPECT_EQ(inputs.clash(dir.file("a.img")),
            dir.file("a.img") +
                ": is also an input of this command; refusing to overwrite it: give another file");
  // The same file by another name: ./, a detour through the parent, a hard and a soft link.
  const std::string detour =
      dir.path() + "/../" + fs::path(dir.path()).filename().string() + "/a.img";
  for (const std::string& path :
       {dir.path() + "/./a.img", detour, dir.file("hard.img"), dir.file("soft.img")}) {
    EXPECT_NE(inputs.clash(path).find("is also an input of this command (" + dir.file("a.img")),
              std::string::npos)
        << path;
  }
  EXPECT_EQ(inputs.clash(dir.file("b.img")), "");
  EXPECT_EQ(inputs.clash(dir.file("new.img")), "");
}

TEST(InputFiles, ASequenceAddsTheImagesItLists) {
  TempDir dir;
  fs::create_directory(dir.file("seq"));
  write_file(dir.file("seq/0001.png"), "not decoded here");
  write_file(dir.file("seq/0002.png"), "not decoded here");
  write_file(dir.file("index.txt"), "seq/0002.png\n");
  InputFiles from_dir;
  from_dir.add_sequence(dir.file("seq"));
  EXPECT_NE(from_dir.clash(dir.file("seq/0001.png")), "");
  InputFiles from_index;
  from_index.add_sequence(dir.file("index.txt"));
  EXPECT_NE(from_index.clash(dir.file("index.txt")), "");
  EXPECT_NE(from_index.clash(dir.file("seq/0002.png")), "");
  EXPECT_EQ(from_index.clash(dir.file("seq/0001.png")), "");
}

// SIGTERM while a temporary is open: the temporary is removed, the old file is untouched,
// and the process still dies of the signal.
TEST(OutputFile, ASignalRemovesTheTemporaries) {
  TempDir dir;
  const std::string stream_path = dir.file("out.csv");
  const std::string image_path = dir.file("card.img");
  write_file(stream_path, "old\n");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    OutputFile out;
    OutputPath image;
    if (!out.open(stream_path).empty() || !image.open(image_path).empty()) _exit(3);
    out.write(std::string_view("new\n"));
    out.flush();
    if (FILE* f = fopen(image.write_path().c_str(), "wb")) {
      fputs("half an image", f);
      fclose(f);
    }
    raise(SIGTERM);
    _exit(4);  // not reached
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status)) << "exit status " << WEXITSTATUS(status);
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  EXPECT_EQ(to_string(read_file(stream_path)), "old\n");
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"out.csv"});
}

// One writer at a time (issue 34). flock locks belong to an open file, so a second OutputFile
// in this process stands in for a second process.
TEST(OutputFile, ASecondWriterOfTheSameFileIsRefused) {
  TempDir dir;
  const std::string path = dir.file("out.csv");
  write_file(path, "old\n");
  OutputFile first;
  ASSERT_EQ(first.open(path), "");
  first.write(std::string_view("first\n"));
  OutputFile second;
  const std::string refused = second.open(path);
  EXPECT_NE(refused.find(path + ": in use by another process"), std::string::npos) << refused;
  EXPECT_FALSE(second.is_open());
  EXPECT_EQ(first.commit(), "");
  EXPECT_EQ(to_string(read_file(path)), "first\n");
  // Once the first has finished, the file is free.
  ASSERT_EQ(second.open(path), "");
  EXPECT_EQ(second.commit(), "");
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"out.csv"});
  // Appended in place (a resumable sweep): refused the same way, and nothing appended.
  OutputFile rows;
  ASSERT_EQ(rows.open(path, OutputFile::Mode::kAppend), "");
  OutputFile more;
  EXPECT_NE(more.open(path, OutputFile::Mode::kAppend).find("in use by another process"),
            std::string::npos);
  OutputPath image;
  EXPECT_NE(image.open(path).find("in use by another process"), std::string::npos);
  EXPECT_EQ(rows.commit(), "");
  EXPECT_EQ(to_string(read_file(path)), "");
}

// A new file that another process created while this one wrote it is not replaced.
TEST(OutputFile, ANewTargetCreatedMeanwhileIsNotReplaced) {
  TempDir dir;
  const std::string path = dir.file("new.json");
  OutputFile out;
  ASSERT_EQ(out.open(path), "");
  out.write(std::string_view("mine"));
  write_file(path, "theirs");
  const std::string error = out.commit();
  EXPECT_NE(error.find(path + ": another process created it while this one was writing it"),
            std::string::npos)
      << error;
  EXPECT_EQ(to_string(read_file(path)), "theirs");
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"new.json"});
  OutputPath image;
  ASSERT_EQ(image.open(dir.file("new.img")), "");
  write_file(image.write_path(), "mine");
  write_file(dir.file("new.img"), "theirs");
  EXPECT_NE(image.commit().find("another process created it"), std::string::npos);
  EXPECT_EQ(to_string(read_file(dir.file("new.img"))), "theirs");
}

// A card opened for writing holds its lock: a second writer (a second firmware, config
// write) is refused before it changes a byte; readers still read it.
TEST(FileBlockDevice, ACardIsWrittenByOneProcessAtATime) {
  TempDir dir;
  const std::string path = dir.file("card.img");
  write_file(path, std::string(2048, 'c'));
  hal::FileBlockDevice first;
  ASSERT_EQ(first.open(path, true), Status::kOk) << first.error();
  hal::FileBlockDevice second;
  EXPECT_EQ(second.open(path, true), Status::kUnavailable);
  EXPECT_NE(second.error().find(path + ": in use by another process"), std::string::npos);
  EXPECT_EQ(second.create(path, 8), Status::kUnavailable);  // not truncated either
  EXPECT_EQ(to_string(read_file(path)), std::string(2048, 'c'));
  hal::FileBlockDevice reader;
  EXPECT_EQ(reader.open(path, false), Status::kOk);
  first.close();
  EXPECT_EQ(second.open(path, true), Status::kOk);
  // A FIFO is no card (opening it would wait for a writer).
  const std::string fifo = dir.file("pipe");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  hal::FileBlockDevice pipe;
  EXPECT_EQ(pipe.open(fifo, false), Status::kInvalidArgument);
  EXPECT_NE(pipe.error().find("is a FIFO or socket"), std::string::npos);
}

// Under a file size limit with SIGXFSZ at its default action: the write fails with EFBIG,
// named, the temporary removed, the old file kept (instead of the signal killing the process).
TEST(OutputFile, AFileSizeLimitIsAWriteError) {
  TempDir dir;
  const std::string path = dir.file("out.bin");
  write_file(path, "old");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    signal(SIGXFSZ, SIG_DFL);
    const struct rlimit limit = {4096, 4096};
    if (setrlimit(RLIMIT_FSIZE, &limit) != 0) _exit(3);
    OutputFile out;
    if (!out.open(path).empty()) _exit(4);
    out.write(std::string(8192, 'x'));
    const std::string error = out.commit();
    const std::string card = hal::check_file_size_limit(path, 8192);
    _exit(error == path + ": write failed: File too large" &&
                  card == path +
                              ": the file size limit (ulimit -f) is 4096 bytes, and writing "
                              "it needs 8192: File too large" &&
                  hal::check_file_size_limit(path, 4096).empty()
              ? 0
              : 5);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(to_string(read_file(path)), "old");
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"out.bin"});
}

TEST(FinishStdout, ReportsAFullStandardOutput) {
  if (!exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  // In a child, with standard output on /dev/full.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    if (freopen("/dev/full", "w", stdout) == nullptr) _exit(3);
    std::printf("a line that cannot be written\n");
    const std::string message = finish_stdout();
    _exit(message == "writing standard output: No space left on device" ? 0 : 5);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(finish_stdout(), "");  // this process's standard output is fine
}

}  // namespace
}  // namespace seqslam::tools
