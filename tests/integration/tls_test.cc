// TLS end to end: a real rmapd with a certificate made here by the openssl
// command line serves robots over wss:// and queries over https://, refuses
// plain connections and clients that do not trust it, and refuses to start
// with missing, unreadable or mismatched files.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "api_helpers.h"
#include "rmap_cli.h"
#include "rmapd_process.h"
#include "scene_clouds.h"

namespace rmap::testing {
namespace {

namespace fs = std::filesystem;

/// A self-signed certificate for 127.0.0.1 (its subjectAltName) and its key.
struct Certificate {
  fs::path certificate_file;
  fs::path private_key_file;
};

Certificate makeCertificate(const fs::path& dir, const std::string& name) {
  const Certificate made{dir / (name + ".pem"), dir / (name + ".key")};
  // An EC key: RSA key generation would take most of the test's time.
  const std::string command = "openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 2 "
                              "-subj /CN=127.0.0.1 -addext subjectAltName=IP:127.0.0.1 -keyout '" +
                              made.private_key_file.string() + "' -out '" + made.certificate_file.string() +
                              "' 2> '" + (dir / (name + ".log")).string() + "'";
  if (std::system(command.c_str()) != 0) {
    throw std::runtime_error("openssl could not make a certificate: " + fileText(dir / (name + ".log")));
  }
  return made;
}

std::string tlsYaml(const fs::path& certificate_file, const fs::path& private_key_file) {
  return std::string(kRoleTokensYaml) + "tls:\n  certificate_file: " + certificate_file.string() +
         "\n  private_key_file: " + private_key_file.string() + "\n";
}

class Tls : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("rmap-tls");
    server_ = new Certificate(makeCertificate(dir_->path(), "server"));
    stranger_ = new Certificate(makeCertificate(dir_->path(), "stranger"));
  }
  static void TearDownTestSuite() {
    delete stranger_;
    delete server_;
    delete dir_;
  }

  void SetUp() override {
    rmapd_ = std::make_unique<RmapdProcess>(
        data_.path() / "data", tlsYaml(server_->certificate_file, server_->private_key_file));
  }

  std::string url(const std::string& scheme) const {
    return scheme + "://127.0.0.1:" + std::to_string(rmapd_->port());
  }

  client::RobotClientOptions robotOptions(const std::string& scheme, const fs::path& ca_file) const {
    client::RobotClientOptions options;
    options.server_url = url(scheme);
    options.ca_file = ca_file.string();
    options.token = "robot-token-1";
    options.hello.set_robot_id("bot-1");
    options.hello.set_map("secure");
    options.timeout = std::chrono::milliseconds(5000);
    return options;
  }

  /// rmapd still answers over https:// (the refused client did not hurt it).
  void expectServingOverTls() {
    ASSERT_TRUE(rmapd_->running());
    client::HttpClient https(url("https"), {}, std::chrono::milliseconds(5000), server_->certificate_file.string());
    EXPECT_EQ(getJson(https, "/healthz")["status"], "ok");
  }

  static TempDir* dir_;
  static Certificate* server_;
  static Certificate* stranger_;
  TempDir data_{"rmap-tls-data"};
  std::unique_ptr<RmapdProcess> rmapd_;
};

TempDir* Tls::dir_ = nullptr;
Certificate* Tls::server_ = nullptr;
Certificate* Tls::stranger_ = nullptr;

TEST_F(Tls, RobotStreamsOverWssAndQueriesAnswerOverHttps) {
  const std::vector<v1::RobotMessage> clouds = sceneClouds(client::makeSimScene(3), 2, 5);
  client::RobotClient robot(robotOptions("wss", server_->certificate_file));
  uint64_t acked_seq = 0;
  robot.onAck([&](const v1::Ack& ack, std::chrono::nanoseconds) { acked_seq = ack.seq(); });
  EXPECT_EQ(robot.connect().last_durable_seq(), 0u);
  for (const v1::RobotMessage& cloud : clouds) robot.send(cloud);
  ASSERT_TRUE(robot.waitAllAcked(std::chrono::seconds(30)));
  EXPECT_EQ(robot.ackedCount(), clouds.size());
  EXPECT_EQ(acked_seq, clouds.size());
  robot.close();

  client::HttpClient https(url("https"), "viewer-token-1", std::chrono::milliseconds(5000),
                           server_->certificate_file.string());
  const nlohmann::json map = getJson(https, "/v1/maps/secure");
  EXPECT_EQ(map["name"], "secure");
  EXPECT_GT(map["version"].get<uint64_t>(), 0u);
  const nlohmann::json robots = getJson(https, "/v1/robots/bot-1");
  EXPECT_EQ(robots["robot_id"], "bot-1");
  // Tokens are checked over TLS as over plain TCP.
  client::HttpClient anonymous(url("https"), {}, std::chrono::milliseconds(5000), server_->certificate_file.string());
  EXPECT_EQ(anonymous.get("/v1/maps").status, 401);

  // The rmap CLI's map commands over https:// with --ca-file: every cuboid of the map.
  const nlohmann::json& bounds = map["bounds"];
  std::ostringstream box;
  box.precision(17);
  for (const char* corner : {"min", "max"}) {
    for (int a = 0; a < 3; ++a) box << (box.tellp() > 0 ? "," : "") << bounds[corner][a].get<double>();
  }
  const CliRun query = runRmap("query --server " + url("https") + " --ca-file '" +
                                   server_->certificate_file.string() +
                                   "' --token viewer-token-1 --map secure --json --box=" + box.str(),
                               data_.path());
  ASSERT_EQ(query.exit_code, 0) << query.err;
  // (Not compared with a count of our own: an idle map fuses its blocks, so the count may move.)
  const nlohmann::json cuboids = nlohmann::json::parse(query.out)["cuboids"];
  ASSERT_FALSE(cuboids.empty()) << query.out;
  EXPECT_TRUE(cuboids.front().contains("probability")) << cuboids.front();

  // A stop with a wss:// stream open closes it (TLS close handshake included) and exits cleanly.
  client::RobotClient open_robot(robotOptions("wss", server_->certificate_file));
  open_robot.connect();
  const auto stop_start = std::chrono::steady_clock::now();
  EXPECT_EQ(rmapd_->terminate(), 0) << rmapd_->log();
  EXPECT_LT(std::chrono::steady_clock::now() - stop_start, std::chrono::seconds(10));
}

TEST_F(Tls, PlainConnectionsAreRefusedAtOnce) {
  // Plain HTTP and ws:// reach a TLS port: the handshake fails, the connection
  // closes without an HTTP answer, well before any timeout.
  client::HttpClient http(url("http"), "viewer-token-1", std::chrono::milliseconds(5000));
  try {
    http.get("/healthz");
    ADD_FAILURE() << "plain HTTP got an answer from a TLS port";
  } catch (const client::ClientError& e) {
    EXPECT_EQ(std::string(e.what()).find("timed out"), std::string::npos) << e.what();
  }
  client::RobotClient plain_robot(robotOptions("ws", {}));
  try {
    plain_robot.connect();
    ADD_FAILURE() << "a ws:// robot connected to a TLS port";
  } catch (const client::ClientError& e) {
    EXPECT_EQ(std::string(e.what()).find("timed out"), std::string::npos) << e.what();
  }
  expectServingOverTls();
}

TEST_F(Tls, AClientThatDoesNotTrustTheCertificateFailsVerification) {
  client::HttpClient https(url("https"), "viewer-token-1", std::chrono::milliseconds(5000),
                           stranger_->certificate_file.string());
  try {
    https.get("/v1/maps");
    ADD_FAILURE() << "https:// accepted a certificate outside its CA file";
  } catch (const client::ClientError& e) {
    EXPECT_NE(std::string(e.what()).find("certificate verify failed"), std::string::npos) << e.what();
  }
  client::RobotClient robot(robotOptions("wss", stranger_->certificate_file));
  try {
    robot.connect();
    ADD_FAILURE() << "wss:// accepted a certificate outside its CA file";
  } catch (const client::ClientError& e) {
    EXPECT_NE(std::string(e.what()).find("certificate verify failed"), std::string::npos) << e.what();
  }
  // The certificate is trusted but names 127.0.0.1, not "localhost".
  client::HttpClient wrong_name("https://localhost:" + std::to_string(rmapd_->port()), {},
                                std::chrono::milliseconds(5000), server_->certificate_file.string());
  EXPECT_THROW(wrong_name.get("/healthz"), client::ClientError);
  expectServingOverTls();
}

/// rmapd run to its exit with `config_yaml`: the exit code and its stderr.
CliRun runRmapd(const fs::path& dir, const std::string& config_yaml) {
  const fs::path config = dir / "bad-tls.yaml";
  std::ofstream(config) << config_yaml;
  const fs::path err = dir / "rmapd.err";
  const std::string command = std::string(rmapdPath()) + " --listen 127.0.0.1:0 --data-dir '" +
                              (dir / "never").string() + "' --config '" + config.string() + "' > /dev/null 2> '" +
                              err.string() + "'";
  const int status = std::system(command.c_str());
  CliRun run;
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.err = fileText(err);
  return run;
}

TEST_F(Tls, BadFilesStopTheStartWithAMessage) {
  const fs::path dir = data_.path();
  const fs::path not_pem = dir / "not.pem";
  std::ofstream(not_pem) << "this is no certificate\n";
  const fs::path missing = dir / "missing.pem";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {tlsYaml(missing, server_->private_key_file),
       "tls: certificate file " + missing.string() + " cannot be read: No such file or directory"},
      {tlsYaml(server_->certificate_file, missing),
       "tls: private key file " + missing.string() + " cannot be read: No such file or directory"},
      {tlsYaml(not_pem, server_->private_key_file),
       "tls: certificate file " + not_pem.string() + " holds no PEM certificate"},
      {tlsYaml(server_->certificate_file, not_pem),
       "tls: private key file " + not_pem.string() + " holds no unencrypted PEM private key"},
      {tlsYaml(server_->certificate_file, stranger_->private_key_file),
       "tls: private key file " + stranger_->private_key_file.string() + " does not belong to certificate " +
           server_->certificate_file.string()},
      {std::string(kRoleTokensYaml) + "tls:\n  certificate_file: " + server_->certificate_file.string() + "\n",
       "tls needs both certificate_file and private_key_file"},
  };
  for (const auto& [yaml, message] : cases) {
    const CliRun run = runRmapd(dir, yaml);
    EXPECT_EQ(run.exit_code, 2) << yaml << run.err;
    EXPECT_NE(run.err.find(message), std::string::npos) << "expected: " << message << "\ngot: " << run.err;
  }
  EXPECT_FALSE(fs::exists(dir / "never")) << "a refused start created the data directory";
}

}  // namespace
}  // namespace rmap::testing
