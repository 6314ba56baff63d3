#include "lodestone/plugin/output/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "lodestone/core/base/error.h"

namespace lodestone::output {

void writeFileAtomically(const std::string& path, const void* data, std::size_t size) {
  if (path.empty()) throw Error("cannot write a file with an empty path");
  if (data == nullptr && size > 0) throw Error(concat("cannot write '", path, "': no data (null pointer)"));
  const std::filesystem::path target(path);
  if (!target.has_filename()) throw Error(concat("cannot write '", path, "': the path names a directory"));
  // Hidden temporary next to the target; mkstemp picks a unique suffix.
  std::string temp = (target.parent_path() / ("." + target.filename().string() + ".tmp-XXXXXX")).string();
  const int fd = ::mkstemp(temp.data());
  if (fd < 0) {
    const int err = errno;
    throw Error(concat("cannot write '", path, "': cannot create a temporary file in its directory (",
                       std::strerror(err), ")"));
  }
  // mkstemp creates the file with mode 0600: keep the mode of the file being
  // replaced, else use rw-r--r-- (reading the umask is not thread-safe).
  struct stat existing {};
  (void)::fchmod(fd, ::stat(path.c_str(), &existing) == 0 ? (existing.st_mode & 07777) : 0644);

  const auto* bytes = static_cast<const char*>(data);
  std::size_t done = 0;
  int err = 0;
  while (done < size) {
    const ssize_t n = ::write(fd, bytes + done, size - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      err = errno;
      break;
    }
    done += std::size_t(n);
  }
  if (::close(fd) != 0 && err == 0) err = errno;
  if (err == 0 && std::rename(temp.c_str(), path.c_str()) != 0) err = errno;
  if (err != 0) {
    std::remove(temp.c_str());
    throw Error(concat("cannot write '", path, "' (", std::strerror(err), ")"));
  }
}

}  // namespace lodestone::output
