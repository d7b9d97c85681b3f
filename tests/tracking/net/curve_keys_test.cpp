// The camera network's key files: ZeroMQ's certificate format written and read back, a
// certificate written by another tool read, and every bad file refused with its name and reason.

#include <filesystem>
#include <fstream>
#include <string>

#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "tests/support/TempDir.h"
#include "tracking/net/CurveKeys.h"

namespace rhot {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_text(const fs::path& p, const std::string& text, mode_t mode = 0600) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
  ::chmod(p.c_str(), mode);
}

unsigned mode_of(const fs::path& p) {
  struct stat st {};
  ::stat(p.c_str(), &st);
  return st.st_mode & 0777;
}

// The client key pair of ZeroMQ's CURVE documentation (zmq_curve(7)), in a certificate laid out
// as CZMQ's zcert writes one: another tool's file.
const std::string kDocPublic = "Yne@$w-vo<fVvi]a<NY6T1ed:M$fCG*[IaLV{hID";
const std::string kDocSecret = "D:)Q[IlAW!ahhC2ac:9*A}h:p?([4%wOTJ%JR%cs";
std::string czmq_secret_certificate() {
  return "#   ****  Generated on 2021-01-01 00:00:00 by CZMQ  ****\n"
         "#   ZeroMQ CURVE **Secret** Certificate\n"
         "#   DO NOT PROVIDE THIS FILE TO OTHER USERS nor change its permissions.\n"
         "\n"
         "metadata\n"
         "    name = \"client\"\n"
         "curve\n"
         "    public-key = \"" +
         kDocPublic + "\"\n    secret-key = \"" + kDocSecret + "\"\n";
}

TEST(CurveKeys, AKeyPairIsWrittenInZeroMqsCertificateFormatAndReadBack) {
  const fs::path dir = test::fresh_test_dir("CurveKeys");
  auto pair = make_key_pair("node0");
  ASSERT_TRUE(pair.has_value()) << pair.error();
  ASSERT_TRUE(write_certificates(dir.string(), *pair).has_value());
  const fs::path pub = dir / "node0.key", sec = dir / "node0.key_secret";
  EXPECT_EQ(mode_of(sec), 0600u) << "the secret key is its owner's alone";
  EXPECT_EQ(mode_of(pub), 0644u);
  const std::string pub_text = read_text(pub), sec_text = read_text(sec);
  EXPECT_NE(pub_text.find("metadata\n    name = \"node0\"\ncurve\n    public-key = \"" + pair->public_key.z85() + "\"\n"),
            std::string::npos)
      << pub_text;
  EXPECT_EQ(pub_text.find("secret-key"), std::string::npos) << "the public certificate holds no secret";
  EXPECT_NE(sec_text.find("    secret-key = \"" + pair->secret_key->z85() + "\"\n"), std::string::npos) << sec_text;

  const auto read_pub = read_certificate(pub.string(), false);
  ASSERT_TRUE(read_pub.has_value()) << read_pub.error();
  EXPECT_EQ(read_pub->name, "node0");
  EXPECT_EQ(read_pub->public_key, pair->public_key);
  EXPECT_FALSE(read_pub->secret_key.has_value());
  const auto read_sec = read_certificate(sec.string(), true);
  ASSERT_TRUE(read_sec.has_value()) << read_sec.error();
  EXPECT_EQ(*read_sec->secret_key, *pair->secret_key);
  // Two pairs are never the same key.
  EXPECT_NE(make_key_pair("node1")->public_key, pair->public_key);
  // A key is never overwritten: replacing one is done on purpose, by removing it.
  const auto again = write_certificates(dir.string(), *make_key_pair("node0"));
  ASSERT_FALSE(again.has_value());
  EXPECT_EQ(again.error(), pub.string() + ": already exists; remove it first to make a new key");
  EXPECT_EQ(read_certificate(sec.string(), true)->secret_key, pair->secret_key);
}

TEST(CurveKeys, ACertificateWrittenByAnotherToolIsRead) {
  const fs::path dir = test::fresh_test_dir("CurveKeys");
  write_text(dir / "client.key_secret", czmq_secret_certificate());
  const auto c = read_certificate((dir / "client.key_secret").string(), true);
  ASSERT_TRUE(c.has_value()) << c.error();
  EXPECT_EQ(c->public_key.z85(), kDocPublic);
  EXPECT_EQ(c->secret_key->z85(), kDocSecret);
}

TEST(CurveKeys, AKeyFolderIsItsOwnSecretAndTheTrustedPeers) {
  const fs::path dir = test::fresh_test_dir("CurveKeys");
  const auto master = make_key_pair("master"), node0 = make_key_pair("node0"), node1 = make_key_pair("node1");
  ASSERT_TRUE(write_certificates((dir / "master").string(), *master).has_value());
  ASSERT_TRUE(write_certificates((dir / "nodes").string(), *node0).has_value());
  ASSERT_TRUE(write_certificates((dir / "nodes").string(), *node1).has_value());
  fs::create_directories(dir / "master" / "trusted");
  fs::copy_file(dir / "nodes" / "node1.key", dir / "master" / "trusted" / "node1.key");
  fs::copy_file(dir / "nodes" / "node0.key", dir / "master" / "trusted" / "node0.key");
  const auto ring = load_key_ring((dir / "master").string());
  ASSERT_TRUE(ring.has_value()) << ring.error();
  EXPECT_EQ(ring->own.name, "master");
  ASSERT_EQ(ring->trusted.size(), 2u);
  EXPECT_EQ(ring->trusted[0].name, "node0") << "sorted by name";
  ASSERT_NE(ring->trusted_named("node1"), nullptr);
  EXPECT_EQ(ring->trusted_named("node1")->public_key, node1->public_key);
  EXPECT_EQ(ring->trusted_named("node2"), nullptr);
  EXPECT_TRUE(ring->trusts(node0->public_key));
  EXPECT_FALSE(ring->trusts(master->public_key));
}

TEST(CurveKeys, BadKeyFilesAndFoldersAreRefusedNamingTheFile) {
  const fs::path dir = test::fresh_test_dir("CurveKeys");
  const fs::path& d = dir;
  const std::string good_pub = "metadata\n    name = \"x\"\ncurve\n    public-key = \"" + kDocPublic + "\"\n";
  const auto refused = [](const std::expected<Certificate, std::string>& r) { return r.has_value() ? std::string("(read)") : r.error(); };

  write_text(d / "open.key_secret", czmq_secret_certificate(), 0644);
  EXPECT_EQ(refused(read_certificate((d / "open.key_secret").string(), true)),
            (d / "open.key_secret").string() + ": a secret key other users can read or write (mode 0644); chmod 600 " +
                (d / "open.key_secret").string());
  std::string mismatched = czmq_secret_certificate();
  mismatched.replace(mismatched.find(kDocPublic), kDocPublic.size(), "rq:rM>}U?@Lns47E1%kR.o@n%FcmmsL/@{H8]yf7");
  write_text(d / "mismatch.key_secret", mismatched);
  EXPECT_EQ(refused(read_certificate((d / "mismatch.key_secret").string(), true)),
            (d / "mismatch.key_secret").string() + ": public-key does not belong to secret-key");
  write_text(d / "short.key", "curve\n    public-key = \"" + kDocPublic.substr(0, 39) + "\"\n");
  EXPECT_EQ(refused(read_certificate((d / "short.key").string(), false)),
            (d / "short.key").string() + ": public-key is not a key (40 characters of Z85)");
  write_text(d / "notz85.key", "curve\n    public-key = \"" + std::string(40, '~') + "\"\n");
  EXPECT_EQ(refused(read_certificate((d / "notz85.key").string(), false)),
            (d / "notz85.key").string() + ": public-key is not a key (40 characters of Z85)");
  write_text(d / "none.key", "metadata\n    name = \"x\"\n");
  EXPECT_EQ(refused(read_certificate((d / "none.key").string(), false)),
            (d / "none.key").string() + ": no public-key in its curve section (not a ZeroMQ certificate?)");
  write_text(d / "tab.key", "curve\n\tpublic-key = \"" + kDocPublic + "\"\n");
  EXPECT_EQ(refused(read_certificate((d / "tab.key").string(), false)),
            (d / "tab.key").string() + ":2: a tab (ZeroMQ's certificates indent by four spaces)");
  write_text(d / "quote.key", "curve\n    public-key = \"" + kDocPublic + "\n");
  EXPECT_EQ(refused(read_certificate((d / "quote.key").string(), false)), (d / "quote.key").string() + ":2: a value's quote is not closed");
  write_text(d / "pubonly.key_secret", good_pub);
  EXPECT_EQ(refused(read_certificate((d / "pubonly.key_secret").string(), true)),
            (d / "pubonly.key_secret").string() + ": no secret-key in its curve section (a public certificate?)");
  write_text(d / "leaky.key", czmq_secret_certificate());
  EXPECT_EQ(refused(read_certificate((d / "leaky.key").string(), false)),
            (d / "leaky.key").string() + ": holds a secret key; give peers only the public certificate (NAME.key)");
  EXPECT_EQ(refused(read_certificate((d / "missing.key").string(), false)), (d / "missing.key").string() + ": No such file or directory");

  // Folders.
  EXPECT_EQ(load_key_ring((d / "nowhere").string()).error(),
            (d / "nowhere").string() + ": no such folder (a key folder: rhot-node keygen --out DIR --name NAME)");
  fs::create_directories(d / "empty");
  EXPECT_EQ(load_key_ring((d / "empty").string()).error(), (d / "empty").string() +
                                                               ": no NAME.key_secret (this program's own key; rhot-node keygen --out " +
                                                               (d / "empty").string() + " --name NAME makes one)");
  write_text(d / "two" / "a.key_secret", czmq_secret_certificate());
  write_text(d / "two" / "b.key_secret", czmq_secret_certificate());
  EXPECT_EQ(load_key_ring((d / "two").string()).error(),
            (d / "two").string() + ": 2 secret keys (a.key_secret, b.key_secret): keep this program's own only");
  write_text(d / "lonely" / "me.key_secret", czmq_secret_certificate());
  EXPECT_EQ(load_key_ring((d / "lonely").string()).error(),
            (d / "lonely" / "trusted").string() + ": no such folder (it holds the public certificates, NAME.key, of the peers to trust)");
  fs::create_directories(d / "lonely" / "trusted");
  EXPECT_EQ(load_key_ring((d / "lonely").string()).error(),
            (d / "lonely" / "trusted").string() + ": no public certificates (NAME.key): this program would trust no one");
  write_text(d / "lonely" / "trusted" / "peer.key_secret", czmq_secret_certificate());
  EXPECT_EQ(load_key_ring((d / "lonely").string()).error(), (d / "lonely" / "trusted" / "peer.key_secret").string() +
                                                                ": a secret key among the trusted; give peers only public certificates");
  fs::remove(d / "lonely" / "trusted" / "peer.key_secret");
  write_text(d / "lonely" / "trusted" / "peer.key", "curve\n    public-key = \"short\"\n");
  EXPECT_EQ(load_key_ring((d / "lonely").string()).error(),
            (d / "lonely" / "trusted" / "peer.key").string() + ": public-key is not a key (40 characters of Z85)");
  // Names.
  EXPECT_EQ(check_key_name("node 1").error(), "key name \"node 1\": only letters, digits, _ . and - (not ' ')");
  EXPECT_EQ(check_key_name("../x").error(), "key name \"../x\": begins with a dot");
  EXPECT_EQ(check_key_name("").error(), "key name \"\": 1 to 64 characters");
}

}  // namespace
}  // namespace rhot
