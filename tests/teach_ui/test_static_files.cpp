// resolve_web_path: traversal, escapes, hidden files and symbolic links
// (teach_ui/static_files.hpp).
#include <gtest/gtest.h>

#include <fstream>

#include "teach_ui/static_files.hpp"

namespace pepper::teach_ui {
namespace {

namespace fs = std::filesystem;

class StaticFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ =
        fs::temp_directory_path() /
        ("pepper_ui_static_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(base_);
    fs::create_directories(base_ / "root" / "sub");
    write(base_ / "root" / "index.html", "<html>index</html>");
    write(base_ / "root" / "sub" / "a b.js", "js");
    write(base_ / "root" / ".hidden", "hidden");
    write(base_ / "secret.txt", "secret");
    fs::create_symlink(base_ / "secret.txt", base_ / "root" / "link.txt");
    root_ = fs::canonical(base_ / "root");
  }
  void TearDown() override { fs::remove_all(base_); }
  static void write(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

  fs::path base_;
  fs::path root_;
};

TEST_F(StaticFiles, ServesFilesAndIndex) {
  EXPECT_EQ(resolve_web_path(root_, "/index.html").status, WebPathStatus::kOk);
  const WebPath index = resolve_web_path(root_, "/");
  ASSERT_EQ(index.status, WebPathStatus::kOk);
  EXPECT_EQ(index.path, root_ / "index.html");
  const WebPath escaped = resolve_web_path(root_, "/sub/a%20b.js?v=3#x");
  ASSERT_EQ(escaped.status, WebPathStatus::kOk);
  EXPECT_EQ(escaped.path, root_ / "sub" / "a b.js");
  EXPECT_EQ(resolve_web_path(root_, "/./sub//a%20b.js").status, WebPathStatus::kOk);
}

TEST_F(StaticFiles, MissingIsNotFound) {
  EXPECT_EQ(resolve_web_path(root_, "/nope.html").status, WebPathStatus::kNotFound);
  EXPECT_EQ(resolve_web_path(root_, "/sub").status, WebPathStatus::kNotFound);   // a folder
  EXPECT_EQ(resolve_web_path(root_, "/sub/").status, WebPathStatus::kNotFound);  // no index
}

TEST_F(StaticFiles, TraversalIsRefused) {
  for (const char* target :
       {"/../secret.txt", "/sub/../../secret.txt", "/%2e%2e/secret.txt", "/%2E%2E%2Fsecret.txt",
        "/sub/%2e%2e/%2e%2e/secret.txt", "/..%5csecret.txt", "/..\\secret.txt", "/index.html%00",
        "/%zz", "/%2", "secret.txt", "", "//../secret.txt"}) {
    SCOPED_TRACE(target);
    EXPECT_EQ(resolve_web_path(root_, target).status, WebPathStatus::kBadTarget);
  }
}

TEST_F(StaticFiles, SymlinkOutsideRootAndHiddenFilesAreNotServed) {
  EXPECT_EQ(resolve_web_path(root_, "/link.txt").status, WebPathStatus::kNotFound);
  EXPECT_EQ(resolve_web_path(root_, "/.hidden").status, WebPathStatus::kNotFound);
  EXPECT_EQ(resolve_web_path(root_, "/%2ehidden").status, WebPathStatus::kNotFound);
}

TEST(MimeType, KnownAndUnknownExtensions) {
  EXPECT_EQ(mime_type_for("a/index.html"), "text/html; charset=utf-8");
  EXPECT_EQ(mime_type_for("app.js"), "text/javascript; charset=utf-8");
  EXPECT_EQ(mime_type_for("x.png"), "image/png");
  EXPECT_EQ(mime_type_for("x.bin"), "application/octet-stream");
}

}  // namespace
}  // namespace pepper::teach_ui
