#pragma once
// Keys for the camera network's security (docs/camera-nodes.md, "Security"): ZeroMQ's CURVE
// mechanism, Curve25519 key pairs, kept in ZeroMQ's certificate files (the format of CZMQ's
// zcert: ZPL text, a `metadata` section with the key's name and a `curve` section with the keys in
// Z85). `NAME.key` holds the public key and is given to peers; `NAME.key_secret` holds both keys
// and never leaves its machine (written readable by its owner only, and refused otherwise).
//
// A key folder (`--keys DIR`) holds the program's own NAME.key_secret (exactly one) and, in
// DIR/trusted/, the public certificates of the peers it trusts: a node's folder the masters' that
// may read it, a master's folder the nodes' it reads, each found by its file name (NAME.key).
// Every failure names the file and what is wrong with it.

#include <array>
#include <cstdint>
#include <expected>
#include <optional>
#include <string>
#include <vector>

namespace rhot {

struct CurveKey {
  std::array<std::uint8_t, 32> bytes{};
  std::string z85() const;  // ZeroMQ's 40-character text form
  bool operator==(const CurveKey&) const = default;
};

struct Certificate {
  std::string name;  // the file's name without .key / .key_secret
  std::string path;
  CurveKey public_key;
  std::optional<CurveKey> secret_key;  // secret certificates only
};

// A certificate's name: 1-64 of A-Z a-z 0-9 _ . -, not beginning with a dot. Fails naming what is wrong.
[[nodiscard]] std::expected<void, std::string> check_key_name(const std::string& name);

// A new key pair (from the operating system's randomness, through libsodium).
[[nodiscard]] std::expected<Certificate, std::string> make_key_pair(const std::string& name);

// Writes DIR/NAME.key (mode 0644) and DIR/NAME.key_secret (mode 0600), making DIR if needed.
// Refuses to overwrite either file: a key is replaced by removing the old one on purpose.
[[nodiscard]] std::expected<void, std::string> write_certificates(const std::string& dir, const Certificate& pair);

// Reads one certificate file; `secret` asks for a secret one (both keys, which must belong
// together, and a file no other user can read).
[[nodiscard]] std::expected<Certificate, std::string> read_certificate(const std::string& path, bool secret);

struct KeyRing {
  std::string dir;
  Certificate own;                   // with its secret key
  std::vector<Certificate> trusted;  // DIR/trusted/*.key, sorted by name

  const Certificate* trusted_named(const std::string& name) const;
  bool trusts(const CurveKey& public_key) const;
};

// Loads a key folder: exactly one *.key_secret in DIR, at least one *.key in DIR/trusted/ (and no
// secret certificate there).
[[nodiscard]] std::expected<KeyRing, std::string> load_key_ring(const std::string& dir);

// Security on a node's or master's sockets: its key folder, or none for --insecure.
using NetSecurity = std::optional<KeyRing>;

}  // namespace rhot
