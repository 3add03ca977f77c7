#include "seqslam_tools/dataset.h"

#include <sys/stat.h>

#include <filesystem>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "seqslam_tools/reduce.h"
#include "test_util.h"

namespace seqslam::tools {
namespace {

namespace fs = std::filesystem;
using test::TempDir;
using test::write_file;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

TEST(Dataset, ImageExtensions) {
  for (const char* yes :
       {"a.png", "a.PNG", "b.pgm", "c.Ppm", "d.jpg", "e.JPEG", "f.bmp", "x.y.jpg", "dir/g.png"}) {
    EXPECT_TRUE(has_image_extension(yes)) << yes;
  }
  for (const char* no :
       {"a.txt", "png", ".png", "a.png.txt", "a.jpgx", "a.tif", "", "a.", "dir/.jpg"}) {
    EXPECT_FALSE(has_image_extension(no)) << no;
  }
}

TEST(Dataset, ListsDirectorySortedByteWiseNonRecursive) {
  TempDir dir;
  for (const char* name :
       {"b.PNG", "a.jpg", "A.bmp", "z.jpeg", "notes.txt", "c.pgm", "_1.ppm", "10.png", "9.png"}) {
    write_file(dir.file(name), "x");
  }
  fs::create_directory(dir.file("sub.png"));  // a directory, not a file
  write_file(dir.file("sub.png/inner.png"), "x");
  const ImageList list = list_images(dir.path());
  ASSERT_TRUE(list.ok()) << list.error();
  // Byte order: digits < upper case < '_' < lower case.
  EXPECT_THAT(list.value(), ElementsAre(dir.file("10.png"), dir.file("9.png"), dir.file("A.bmp"),
                                        dir.file("_1.ppm"), dir.file("a.jpg"), dir.file("b.PNG"),
                                        dir.file("c.pgm"), dir.file("z.jpeg")));
}

// Issue 34: an image entry that cannot be read is an error naming it, never skipped (which
// shifted every later image's index); subdirectories are still not images.
TEST(Dataset, AnUnreadableImageEntryIsAnError) {
  TempDir dir;
  for (const char* name : {"0001.png", "0003.png"})
    write_file(dir.file(name), "x");
  ASSERT_TRUE(list_images(dir.path()).ok());
  fs::create_symlink("missing.png", dir.file("0002.png"));
  ImageList list = list_images(dir.path());
  ASSERT_FALSE(list.ok());
  EXPECT_THAT(list.error(), HasSubstr(dir.file("0002.png") +
                                      ": a dangling symbolic link (to missing.png, which does "
                                      "not exist) (an image entry of the directory " +
                                      dir.path()));
  fs::remove(dir.file("0002.png"));
  fs::create_symlink("loop_b.jpg", dir.file("loop_a.jpg"));
  fs::create_symlink("loop_a.jpg", dir.file("loop_b.jpg"));
  list = list_images(dir.path());
  ASSERT_FALSE(list.ok());
  EXPECT_THAT(list.error(),
              HasSubstr(": a symbolic link loop (Too many levels of symbolic links)"));
  fs::remove(dir.file("loop_a.jpg"));
  fs::remove(dir.file("loop_b.jpg"));
  ASSERT_EQ(mkfifo(dir.file("0002.png").c_str(), 0600), 0);
  list = list_images(dir.path());
  ASSERT_FALSE(list.ok());
  EXPECT_THAT(list.error(), HasSubstr(dir.file("0002.png") + ": is not a regular file"));
  fs::remove(dir.file("0002.png"));
  // Links that are not images, and a link to a real image, are fine.
  fs::create_symlink("nowhere", dir.file("notes.txt"));
  fs::create_symlink("0001.png", dir.file("0002.png"));
  list = list_images(dir.path());
  ASSERT_TRUE(list.ok()) << list.error();
  EXPECT_EQ(list.value().size(), 3u);
  // A missing directory or index behind a link loop says so, not "no such file".
  fs::create_symlink("loop_d", dir.file("loop_c"));
  fs::create_symlink("loop_c", dir.file("loop_d"));
  EXPECT_THAT(list_images(dir.file("loop_c")).error(), HasSubstr("a symbolic link loop"));
}

TEST(Dataset, DirectoryErrors) {
  TempDir dir;
  const ImageList empty = list_images(dir.path());
  EXPECT_FALSE(empty.ok());
  EXPECT_THAT(empty.error(), HasSubstr(dir.path()));
  EXPECT_THAT(empty.error(), HasSubstr("no images"));

  write_file(dir.file("readme.txt"), "hello");
  EXPECT_THAT(list_images(dir.path()).error(), HasSubstr("no images"));

  const ImageList missing = list_images(dir.file("missing"));
  EXPECT_FALSE(missing.ok());
  EXPECT_THAT(missing.error(), HasSubstr("missing"));
  EXPECT_THAT(missing.error(), HasSubstr("no such file"));
  EXPECT_FALSE(list_images("").ok());
  EXPECT_THAT(list_images("/dev/null").error(), HasSubstr("neither a directory"));
}

TEST(Dataset, IndexFileWithCommentsCrlfWhitespaceAndRelativePaths) {
  TempDir dir;
  fs::create_directories(dir.file("lists"));
  fs::create_directories(dir.file("imgs/sub"));
  for (const char* name : {"imgs/a.png", "imgs/b.jpg", "imgs/sub/c.pgm", "abs.bmp", "lists/d"}) {
    write_file(dir.file(name), "x");
  }
  const std::string index = dir.file("lists/index.txt");
  write_file(index,
             "# sequence for the test\r\n"
             "\r\n"
             "../imgs/b.jpg\r\n"
             "   ../imgs/a.png   \r\n"
             "\t# indented comment\n"
             "../imgs/sub/c.pgm\n"
             "   \n" +
                 dir.file("abs.bmp") +
                 "\n"
                 "d");  // no final newline; any extension is accepted in an index
  const ImageList list = list_images(index);
  ASSERT_TRUE(list.ok()) << list.error();
  const std::string base = dir.file("lists");
  EXPECT_THAT(list.value(),
              ElementsAre(base + "/../imgs/b.jpg", base + "/../imgs/a.png",
                          base + "/../imgs/sub/c.pgm", dir.file("abs.bmp"), base + "/d"));
  for (const std::string& path : list.value())
    EXPECT_TRUE(fs::is_regular_file(path)) << path;
}

TEST(Dataset, IndexFileErrorsNameTheLine) {
  TempDir dir;
  write_file(dir.file("a.png"), "x");
  fs::create_directory(dir.file("folder"));

  write_file(dir.file("missing.txt"), "# header\na.png\n\nb.png\n");
  ImageList list = list_images(dir.file("missing.txt"));
  EXPECT_FALSE(list.ok());
  EXPECT_THAT(list.error(), HasSubstr(dir.file("missing.txt") + ":4:"));
  EXPECT_THAT(list.error(), HasSubstr("'b.png' does not exist"));

  write_file(dir.file("dir.txt"), "a.png\r\nfolder\r\n");
  list = list_images(dir.file("dir.txt"));
  EXPECT_FALSE(list.ok());
  EXPECT_THAT(list.error(), HasSubstr("dir.txt:2:"));
  EXPECT_THAT(list.error(), HasSubstr("not a regular file"));

  write_file(dir.file("nul.txt"), std::string("a.png\nb\0c\n", 10));
  list = list_images(dir.file("nul.txt"));
  EXPECT_FALSE(list.ok());
  EXPECT_THAT(list.error(), HasSubstr("nul.txt:2:"));

  write_file(dir.file("empty.txt"), "");
  EXPECT_THAT(list_images(dir.file("empty.txt")).error(), HasSubstr("lists no images"));
  write_file(dir.file("comments.txt"), "# only\n\n   # comments\r\n");
  EXPECT_THAT(list_images(dir.file("comments.txt")).error(), HasSubstr("lists no images"));

  // An image passed where an index is expected gets a clear message.
  EXPECT_THAT(list_images(dir.file("a.png")).error(), HasSubstr("is an image file"));
}

TEST(Dataset, LoadSequenceFromCorridorDirectory) {
  const LoadedSequence seq = load_sequence(test::corridor_dir() + "/ref", 32, 24);
  ASSERT_TRUE(seq.ok()) << seq.error();
  ASSERT_EQ(seq.value().images.size(), 111u);
  ASSERT_EQ(seq.value().paths.size(), 111u);
  EXPECT_THAT(seq.value().paths.front(), HasSubstr("0000000.jpg"));
  EXPECT_THAT(seq.value().paths.back(), HasSubstr("0000110.jpg"));
  for (const GrayImage& image : seq.value().images) {
    EXPECT_EQ(image.width, 32);
    EXPECT_EQ(image.height, 24);
    EXPECT_TRUE(image.valid());
  }
}

TEST(Dataset, LoadSequenceFromIndexInOrder) {
  TempDir dir;
  const std::string corridor = test::corridor_dir();
  write_file(dir.file("seq.txt"), "# three query frames, out of order\n" + corridor +
                                      "/query/0000005.jpg\n" + corridor + "/query/0000001.jpg\r\n" +
                                      corridor + "/query/0000003.jpg\n");
  const LoadedSequence seq = load_sequence(dir.file("seq.txt"), 16, 12);
  ASSERT_TRUE(seq.ok()) << seq.error();
  ASSERT_EQ(seq.value().images.size(), 3u);
  EXPECT_THAT(seq.value().paths[0], HasSubstr("0000005.jpg"));
  EXPECT_THAT(seq.value().paths[1], HasSubstr("0000001.jpg"));
  EXPECT_EQ(seq.value().images[2].width, 16);
  const LoadedImage direct = load_gray(corridor + "/query/0000005.jpg");
  ASSERT_TRUE(direct.ok());
  EXPECT_EQ(seq.value().images[0].pixels, reduce_to(direct.value(), 16, 12).value().pixels);
}

TEST(Dataset, LoadSequenceErrorsNameTheFile) {
  TempDir dir;
  GrayImage image;
  image.width = 8;
  image.height = 8;
  image.pixels.assign(64, 100);
  ASSERT_TRUE(save_png(dir.file("0.png"), image, nullptr));
  write_file(dir.file("1.png"), "not an image at all");
  LoadedSequence seq = load_sequence(dir.path(), 4, 4);
  EXPECT_FALSE(seq.ok());
  EXPECT_THAT(seq.error(), HasSubstr(dir.file("1.png")));
  EXPECT_TRUE(seq.value().images.empty());

  fs::remove(dir.file("1.png"));
  ASSERT_TRUE(load_sequence(dir.path(), 4, 4).ok());
  // Upscaling: the error names the image and carries the core's status.
  seq = load_sequence(dir.path(), 16, 4);
  EXPECT_FALSE(seq.ok());
  EXPECT_THAT(seq.error(), HasSubstr(dir.file("0.png")));
  EXPECT_THAT(seq.error(), HasSubstr("INVALID_ARGUMENT"));
  // A bad target size is reported before any image is loaded.
  seq = load_sequence(dir.path(), 0, 4);
  EXPECT_FALSE(seq.ok());
  EXPECT_THAT(seq.error(), HasSubstr("positive"));
  seq = load_sequence(dir.file("nothing"), 4, 4);
  EXPECT_THAT(seq.error(), HasSubstr("no such file"));
}

}  // namespace
}  // namespace seqslam::tools
