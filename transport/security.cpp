#include "transport/security.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <tessera/util/input_error.hpp>

namespace tessera::transport {

namespace {

// The absolute form of an existing path (Fast DDS wants file:///absolute URIs).
std::string absolute(const std::string& path) {
  char buf[PATH_MAX];
  if (!realpath(path.c_str(), buf)) return path;
  return buf;
}

std::string need_file(const std::string& dir, const std::string& rel, const std::string& what) {
  const std::string path = absolute(dir) + "/" + rel;
  struct stat st {};
  if (stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
    throw InputError("option --security: missing " + path + " (" + what +
                     "; scripts/security/make_identities.sh writes it)");
  if (access(path.c_str(), R_OK) != 0)
    throw InputError("option --security: cannot read " + path + " (" + what + ")");
  return path;
}

}  // namespace

std::string security_identity(bool coordinator, std::uint32_t agent_id) {
  return coordinator ? std::string("coordinator") : "agent_" + std::to_string(agent_id);
}

void check_security_dir(const std::string& dir) {
  struct stat st {};
  if (dir.empty() || stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw InputError("option --security: '" + dir + "' is not a folder");
  need_file(dir, "ca_cert.pem", "the CA certificate");
  need_file(dir, "governance.p7s", "the signed governance document");
}

SecurityFiles security_files(const std::string& dir, const std::string& identity) {
  check_security_dir(dir);
  SecurityFiles f;
  f.ca_cert = need_file(dir, "ca_cert.pem", "the CA certificate");
  f.governance = need_file(dir, "governance.p7s", "the signed governance document");
  f.cert = need_file(dir, identity + "/cert.pem", "the certificate of " + identity);
  f.key = need_file(dir, identity + "/key.pem", "the private key of " + identity);
  f.permissions =
      need_file(dir, identity + "/permissions.p7s", "the signed permissions of " + identity);
  return f;
}

std::vector<std::pair<std::string, std::string>> security_properties(const SecurityFiles& files) {
  const std::string auth = "dds.sec.auth.builtin.PKI-DH.";
  const std::string access = "dds.sec.access.builtin.Access-Permissions.";
  auto uri = [](const std::string& path) { return "file://" + path; };
  return {
      {"dds.sec.auth.plugin", "builtin.PKI-DH"},
      {auth + "identity_ca", uri(files.ca_cert)},
      {auth + "identity_certificate", uri(files.cert)},
      {auth + "private_key", uri(files.key)},
      {"dds.sec.access.plugin", "builtin.Access-Permissions"},
      {access + "permissions_ca", uri(files.ca_cert)},
      {access + "governance", uri(files.governance)},
      {access + "permissions", uri(files.permissions)},
      {"dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC"},
  };
}

}  // namespace tessera::transport
