#include "tracking/net/CurveKeys.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <sstream>
#include <system_error>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zmq.h>

namespace rhot {

namespace fs = std::filesystem;

namespace {

constexpr std::size_t kZ85KeyChars = 40;
constexpr std::uintmax_t kMaxCertificateBytes = 64 * 1024;

std::optional<CurveKey> decode_z85(const std::string& text) {
  if (text.size() != kZ85KeyChars) return std::nullopt;
  CurveKey key;
  if (zmq_z85_decode(key.bytes.data(), text.c_str()) == nullptr) return std::nullopt;
  return key;
}

std::string certificate_text(const Certificate& c, bool secret) {
  char stamp[32] = "";
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&now, &tm);
  std::strftime(stamp, sizeof stamp, "%Y-%m-%d %H:%M:%S UTC", &tm);
  std::ostringstream out;
  out << "#   Made " << stamp << " by rhot-node keygen (ZeroMQ's certificate format, as CZMQ's zcert)\n";
  if (secret) {
    out << "#   ZeroMQ CURVE **Secret** Certificate\n"
           "#   Keep this file on its own machine, readable by its owner only; never send it to anyone.\n";
  } else {
    out << "#   ZeroMQ CURVE Public Certificate\n"
           "#   Give it to the peers that are to trust this key, over a channel you trust.\n";
  }
  out << "\nmetadata\n    name = \"" << c.name << "\"\ncurve\n    public-key = \"" << c.public_key.z85() << "\"\n";
  if (secret) out << "    secret-key = \"" << c.secret_key->z85() << "\"\n";
  return out.str();
}

std::string errno_text(int e) { return std::generic_category().message(e); }

// Writes a new file with exactly `mode`, never replacing one, and flushes it to the disk: a crash
// leaves the whole key or none (a half-written file is removed).
std::expected<void, std::string> write_new_file(const fs::path& path, const std::string& text, mode_t mode) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
  if (fd < 0) {
    const int e = errno;
    if (e == EEXIST) return std::unexpected(path.string() + ": already exists; remove it first to make a new key");
    return std::unexpected(path.string() + ": cannot create: " + errno_text(e));
  }
  const auto fail = [&](int e) {
    ::close(fd);
    ::unlink(path.c_str());
    return std::unexpected(path.string() + ": cannot write: " + errno_text(e));
  };
  if (::fchmod(fd, mode) != 0) return fail(errno);  // whatever the umask
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return fail(n < 0 ? errno : EIO);
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) return fail(errno);
  if (::close(fd) != 0) {
    const int e = errno;
    ::unlink(path.c_str());
    return std::unexpected(path.string() + ": cannot write: " + errno_text(e));
  }
  return {};
}

// A certificate file's text, read through one descriptor (its checks and its reading are of the
// same file): a regular file of at most kMaxCertificateBytes; a secret one owned by this user and
// neither readable nor writable by anyone else.
std::expected<std::string, std::string> read_certificate_text(const std::string& path, bool secret) {
  // A secret key is never followed through a link; O_NONBLOCK: a FIFO put in its place does not hang.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | (secret ? O_NOFOLLOW : 0));
  if (fd < 0) return std::unexpected(path + ": " + errno_text(errno));
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) return std::unexpected(path + ": " + errno_text(errno));
  if (!S_ISREG(st.st_mode)) return std::unexpected(path + ": not a file");
  if (static_cast<std::uintmax_t>(st.st_size) > kMaxCertificateBytes)
    return std::unexpected(path + ": " + std::to_string(st.st_size) + " bytes, too large for a certificate");
  if (secret && (st.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    return std::unexpected(path + ": a secret key other users can read or write (mode " + mode + "); chmod 600 " + path);
  }
  if (secret && st.st_uid != ::geteuid())
    return std::unexpected(path + ": a secret key owned by another user (uid " + std::to_string(st.st_uid) + ")");
  std::string text(kMaxCertificateBytes + 1, '\0');
  std::size_t got = 0;
  while (got < text.size()) {
    const ssize_t n = ::read(fd, text.data() + got, text.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return std::unexpected(path + ": cannot read: " + errno_text(errno));
    if (n == 0) break;
    got += static_cast<std::size_t>(n);
  }
  if (got > kMaxCertificateBytes) return std::unexpected(path + ": too large for a certificate");
  text.resize(got);
  return text;
}

// The ZPL of a certificate: sections at column 0, `name = value` four spaces in, comments from #.
struct ParsedCertificate {
  std::optional<std::string> name, public_key, secret_key;
};

std::expected<ParsedCertificate, std::string> parse_zpl(const std::string& path, const std::string& text) {
  ParsedCertificate out;
  std::istringstream in(text);
  std::string line, section;
  int number = 0;
  const auto bad = [&](const std::string& why) { return std::unexpected(path + ":" + std::to_string(number) + ": " + why); };
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto first = line.find_first_not_of(' ');
    if (first == std::string::npos || line[first] == '#') continue;
    if (line.find('\t') != std::string::npos) return bad("a tab (ZeroMQ's certificates indent by four spaces)");
    if (first == 0) {
      section = line.substr(0, line.find_first_of(" #"));
      continue;
    }
    if (first != 4) return bad("indented by " + std::to_string(first) + " spaces (four for a section's entries)");
    const auto eq = line.find('=', first);
    if (eq == std::string::npos) return bad("expected NAME = \"VALUE\"");
    std::string key = line.substr(first, eq - first);
    while (!key.empty() && key.back() == ' ') key.pop_back();
    std::string value = line.substr(eq + 1);
    value.erase(0, value.find_first_not_of(' '));
    if (!value.empty() && (value.front() == '"' || value.front() == '\'')) {
      const auto close = value.find(value.front(), 1);
      if (close == std::string::npos) return bad("a value's quote is not closed");
      value = value.substr(1, close - 1);
    } else {
      value = value.substr(0, value.find_first_of(" #"));
    }
    if (section == "metadata" && key == "name") out.name = value;
    if (section == "curve" && key == "public-key") out.public_key = value;
    if (section == "curve" && key == "secret-key") out.secret_key = value;
  }
  return out;
}

}  // namespace

std::string CurveKey::z85() const {
  char text[kZ85KeyChars + 1] = {};
  zmq_z85_encode(text, bytes.data(), bytes.size());
  return text;
}

std::expected<void, std::string> check_key_name(const std::string& name) {
  if (name.empty() || name.size() > 64) return std::unexpected("key name \"" + name + "\": 1 to 64 characters");
  if (name.front() == '.') return std::unexpected("key name \"" + name + "\": begins with a dot");
  for (const char c : name)
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-'))
      return std::unexpected("key name \"" + name + "\": only letters, digits, _ . and - (not '" + std::string(1, c) + "')");
  return {};
}

std::expected<Certificate, std::string> make_key_pair(const std::string& name) {
  if (auto ok = check_key_name(name); !ok) return std::unexpected(ok.error());
  char pub[kZ85KeyChars + 1] = {}, sec[kZ85KeyChars + 1] = {};
  if (zmq_curve_keypair(pub, sec) != 0)
    return std::unexpected(std::string("cannot make a key pair: this libzmq has no CURVE (") + zmq_strerror(zmq_errno()) + ")");
  Certificate c;
  c.name = name;
  c.public_key = *decode_z85(pub);
  c.secret_key = decode_z85(sec);
  return c;
}

std::expected<void, std::string> write_certificates(const std::string& dir, const Certificate& pair) {
  if (auto ok = check_key_name(pair.name); !ok) return std::unexpected(ok.error());
  if (!pair.secret_key) return std::unexpected("key \"" + pair.name + "\": no secret key to write");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) return std::unexpected(dir + ": cannot make the folder" + (ec ? ": " + ec.message() : ""));
  const fs::path pub = fs::path(dir) / (pair.name + ".key"), sec = fs::path(dir) / (pair.name + ".key_secret");
  if (fs::exists(pub, ec)) return std::unexpected(pub.string() + ": already exists; remove it first to make a new key");
  if (auto ok = write_new_file(sec, certificate_text(pair, true), 0600); !ok) return ok;
  if (auto ok = write_new_file(pub, certificate_text(pair, false), 0644); !ok) {
    fs::remove(sec, ec);
    return ok;
  }
  return {};
}

std::expected<Certificate, std::string> read_certificate(const std::string& path, bool secret) {
  const auto text = read_certificate_text(path, secret);
  if (!text) return std::unexpected(text.error());
  auto parsed = parse_zpl(path, *text);
  if (!parsed) return std::unexpected(parsed.error());
  Certificate c;
  c.path = path;
  c.name = fs::path(path).filename().string();
  for (const std::string suffix : {".key_secret", ".key"})
    if (c.name.size() > suffix.size() && c.name.ends_with(suffix)) {
      c.name.resize(c.name.size() - suffix.size());
      break;
    }
  if (!parsed->public_key) return std::unexpected(path + ": no public-key in its curve section (not a ZeroMQ certificate?)");
  const auto pub = decode_z85(*parsed->public_key);
  if (!pub) return std::unexpected(path + ": public-key is not a key (40 characters of Z85)");
  c.public_key = *pub;
  if (secret) {
    if (!parsed->secret_key) return std::unexpected(path + ": no secret-key in its curve section (a public certificate?)");
    c.secret_key = decode_z85(*parsed->secret_key);
    if (!c.secret_key) return std::unexpected(path + ": secret-key is not a key (40 characters of Z85)");
    char derived[kZ85KeyChars + 1] = {};
    const std::string sec = c.secret_key->z85();
    if (zmq_curve_public(derived, sec.c_str()) != 0 || derived != c.public_key.z85())
      return std::unexpected(path + ": public-key does not belong to secret-key");
  } else if (parsed->secret_key) {
    return std::unexpected(path + ": holds a secret key; give peers only the public certificate (NAME.key)");
  }
  return c;
}

const Certificate* KeyRing::trusted_named(const std::string& name) const {
  for (const Certificate& c : trusted)
    if (c.name == name) return &c;
  return nullptr;
}

bool KeyRing::trusts(const CurveKey& public_key) const {
  return std::any_of(trusted.begin(), trusted.end(), [&](const Certificate& c) { return c.public_key == public_key; });
}

std::expected<KeyRing, std::string> load_key_ring(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return std::unexpected(dir + ": no such folder (a key folder: rhot-node keygen --out DIR --name NAME)");
  KeyRing ring;
  ring.dir = dir;
  std::vector<fs::path> secrets, publics;
  for (auto it = fs::directory_iterator(dir, ec); !ec && it != fs::directory_iterator(); it.increment(ec))
    if (it->path().extension() == ".key_secret") secrets.push_back(it->path());
  if (ec) return std::unexpected(dir + ": cannot list: " + ec.message());
  std::sort(secrets.begin(), secrets.end());
  if (secrets.empty())
    return std::unexpected(dir + ": no NAME.key_secret (this program's own key; rhot-node keygen --out " + dir + " --name NAME makes one)");
  if (secrets.size() > 1)
    return std::unexpected(dir + ": " + std::to_string(secrets.size()) + " secret keys (" + secrets[0].filename().string() + ", " +
                           secrets[1].filename().string() + "): keep this program's own only");
  auto own = read_certificate(secrets[0].string(), true);
  if (!own) return std::unexpected(own.error());
  ring.own = std::move(*own);
  const fs::path trusted = fs::path(dir) / "trusted";
  if (!fs::is_directory(trusted, ec))
    return std::unexpected(trusted.string() + ": no such folder (it holds the public certificates, NAME.key, of the peers to trust)");
  for (auto it = fs::directory_iterator(trusted, ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
    if (it->path().extension() == ".key_secret")
      return std::unexpected(it->path().string() + ": a secret key among the trusted; give peers only public certificates");
    if (it->path().extension() == ".key") publics.push_back(it->path());
  }
  if (ec) return std::unexpected(trusted.string() + ": cannot list: " + ec.message());
  std::sort(publics.begin(), publics.end());
  if (publics.empty()) return std::unexpected(trusted.string() + ": no public certificates (NAME.key): this program would trust no one");
  for (const fs::path& p : publics) {
    auto c = read_certificate(p.string(), false);
    if (!c) return std::unexpected(c.error());
    ring.trusted.push_back(std::move(*c));
  }
  return ring;
}

}  // namespace rhot
