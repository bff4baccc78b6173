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

}  // namespace pepper::core::memory::detail
