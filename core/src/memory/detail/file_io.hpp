#pragma once
// Private helper of the core's file formats (maps, ceiling mosaics): write a whole file and
// fsync it, so that a rename of it into place (atomic saves) never exposes a half-written file.
// Errors go to `on_error(path, what)`, which must throw the caller's own error type (MapError,
// MosaicError); the text after "what" is the caller's (it usually appends strerror(errno)).

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <string>
#include <system_error>

namespace pepper::core::memory::detail {

template <typename OnError>
void write_file_synced(const std::filesystem::path& path, const uint8_t* data, size_t size,
                       OnError&& on_error) {
  auto fail = [&](const char* what) {
    on_error(path, std::string(what));
    std::terminate();  // on_error must throw
  };
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) fail("cannot create");
  size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      ::close(fd);
      fail("write failed");
    }
    done += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0) {
    ::close(fd);
    fail("fsync failed");
  }
  if (::close(fd) != 0) fail("close failed");
}

/// Replaces `file` by `text` atomically: a sibling temporary file written and synced, renamed over
/// `file`, then the folder synced; the temporary file is removed on failure. `on_error(path,
/// what)` must throw; errno still holds the failure's cause when it is called. For the single-file
/// formats (the ceiling mosaic and tour); a map is a folder and has its own renaming.
template <typename OnError>
void replace_file_atomically(const std::filesystem::path& file, const std::string& text,
                             OnError&& on_error) {
  const std::filesystem::path dir =
      file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
  const std::filesystem::path tmp =
      dir / (file.filename().string() + ".tmp-" + std::to_string(::getpid()));
  auto remove_tmp_then = [&](const std::filesystem::path& path, const std::string& what) {
    const int cause = errno;  // on_error reports it; the clean-up must not replace it
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    errno = cause;
    on_error(path, what);
  };
  write_file_synced(tmp, reinterpret_cast<const uint8_t*>(text.data()), text.size(),
                    remove_tmp_then);
  if (::rename(tmp.c_str(), file.c_str()) != 0) {
    remove_tmp_then(file, "cannot rename the new file into place");
  }
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

}  // namespace pepper::core::memory::detail
