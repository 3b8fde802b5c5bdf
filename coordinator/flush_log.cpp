#include "coordinator/flush_log.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>

namespace farm {
namespace fs = std::filesystem;

namespace {

// All of `bytes` at `offset` of `fd`, through short writes and interruptions; false with errno
// set when the system refuses.
bool writeFully(int fd, const std::string& bytes, uint64_t offset) {
  for (size_t done = 0; done < bytes.size();) {
    const ssize_t n = ::pwrite(fd, bytes.data() + done, bytes.size() - done, off_t(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += size_t(n);
  }
  return true;
}

}  // namespace

FlushLog::FlushLog(std::string dir) : dir_(std::move(dir)) {}

FlushLog::~FlushLog() {
  for (auto& [id, log] : open_) ::close(log.fd);
}

bool FlushLog::namesAFile(const std::string& id) {
  return !id.empty() && id.find('/') == std::string::npos && id.find("..") == std::string::npos;
}

std::string FlushLog::logPath(const std::string& id) const {
  return (fs::path(dir_) / (id + ".log")).string();
}

Status FlushLog::open(const std::string& id, uint64_t committedEnd) {
  if (isOpen(id)) return Status::ok();
  if (!namesAFile(id)) return Status::invalidArgument("job id '" + id + "' cannot name a log file");
  const std::string path = logPath(id);
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0 || ::ftruncate(fd, off_t(committedEnd)) != 0) {
    const std::string why = std::strerror(errno);
    if (fd >= 0) ::close(fd);
    return Status::internal("cannot open the flush log " + path + ": " + why);
  }
  open_[id] = Open{fd, committedEnd};
  return Status::ok();
}

Status FlushLog::write(const std::string& id, const std::string& record, uint64_t* offset) {
  auto it = open_.find(id);
  if (it == open_.end()) return Status::internal("the flush log of job " + id + " is not open");
  if (!writeFully(it->second.fd, record, it->second.end) || ::fdatasync(it->second.fd) != 0) {
    return Status::internal(logPath(id) + ": " + std::strerror(errno));
  }
  *offset = it->second.end;
  return Status::ok();
}

void FlushLog::commit(const std::string& id, uint64_t bytes) {
  if (auto it = open_.find(id); it != open_.end()) it->second.end += bytes;
}

void FlushLog::reset(const std::string& id) {
  auto it = open_.find(id);
  if (it == open_.end()) return;
  (void)::ftruncate(it->second.fd, 0);  // else the next open cuts them off
  ::close(it->second.fd);
  open_.erase(it);
}

bool FlushLog::Reader::read(uint64_t offset, uint64_t length, std::string* record) {
  if (!in_.is_open()) in_.open(path_, std::ios::binary);
  record->resize(size_t(length));
  return bool(in_.seekg(std::streamoff(offset))) &&
         bool(in_.read(record->data(), std::streamsize(record->size())));
}

Status FlushLog::writeFilm(const std::string& id, uint64_t generation, const std::string& bytes,
                           std::string* name) {
  if (!namesAFile(id)) return Status::invalidArgument("job id '" + id + "' cannot name a file");
  *name = id + "." + std::to_string(generation) + "." + std::to_string(++filmsWritten_) + ".sums";
  const std::string path = (fs::path(dir_) / *name).string();
  const std::string temporary = path + ".tmp";
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Status::internal("cannot write " + temporary + ": " + std::strerror(errno));
  if (!writeFully(fd, bytes, 0)) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    return Status::internal("cannot write " + temporary + ": " + why);
  }
  if (::fdatasync(fd) != 0 || ::close(fd) != 0 || ::rename(temporary.c_str(), path.c_str()) != 0) {
    return Status::internal("cannot write " + path + ": " + std::strerror(errno));
  }
  // The rename is durable once the directory is.
  const int dir = ::open(dir_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  const bool synced = dir >= 0 && ::fsync(dir) == 0;
  if (dir >= 0) ::close(dir);
  if (!synced) return Status::internal("cannot sync " + dir_ + ": " + std::strerror(errno));
  return Status::ok();
}

void FlushLog::discardFilm(const std::string& name) {
  std::error_code ec;
  fs::remove(fs::path(dir_) / name, ec);
}

void FlushLog::adoptFilm(const std::string& id, const std::string& name) {
  auto previous = films_.find(id);
  if (previous != films_.end() && previous->second != name) discardFilm(previous->second);
  films_[id] = name;
}

void FlushLog::removeJob(const std::string& id) {
  reset(id);
  std::error_code ec;
  fs::remove(logPath(id), ec);
  if (auto it = films_.find(id); it != films_.end()) {
    discardFilm(it->second);
    films_.erase(it);
  }
}

void FlushLog::sweep() {
  std::set<std::string> named;
  for (const auto& [job, file] : films_) named.insert(file);
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(dir_, ec)) {
    const std::string file = e.path().filename().string();
    const bool film = e.path().extension() == ".sums" ||
                      (e.path().extension() == ".tmp" && e.path().stem().extension() == ".sums");
    if (film && !named.count(file)) fs::remove(e.path(), ec);
  }
}

}  // namespace farm
