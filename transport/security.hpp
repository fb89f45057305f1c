#pragma once
// DDS Security for a run (`--security DIR`): which files of DIR a participant uses and the
// Fast DDS properties that turn on authentication (builtin.PKI-DH), access control
// (builtin.Access-Permissions: signed governance + permissions) and encryption
// (builtin.AES-GCM-GMAC). The layout of DIR is the one scripts/security/make_identities.sh
// writes (docs/dds-runtime.md, "Security"). No Fast DDS types here: `tessera launch`
// checks a DIR before starting any process.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace tessera::transport {

/// Absolute paths of one participant's security files.
struct SecurityFiles {
  std::string ca_cert;      ///< DIR/ca_cert.pem: identity CA and permissions CA.
  std::string governance;   ///< DIR/governance.p7s: signed domain rules.
  std::string cert;         ///< DIR/<identity>/cert.pem: this participant's certificate.
  std::string key;          ///< DIR/<identity>/key.pem: its private key.
  std::string permissions;  ///< DIR/<identity>/permissions.p7s: its signed permissions.
};

/// The identity (sub-folder of DIR) a process uses: "coordinator" or "agent_<k>".
std::string security_identity(bool coordinator, std::uint32_t agent_id);

/// Throws InputError naming the option and the file unless `dir` is a folder holding the
/// files every participant shares (ca_cert.pem, governance.p7s).
void check_security_dir(const std::string& dir);

/// The files of `identity` in `dir` as absolute paths; throws InputError naming the first
/// missing or unreadable file ("option --security: missing /abs/DIR/agent_1/key.pem ...").
SecurityFiles security_files(const std::string& dir, const std::string& identity);

/// Participant properties (name, value) enabling PKI-DH authentication, Access-Permissions
/// and AES-GCM-GMAC with these files (values are file:///absolute/path URIs).
std::vector<std::pair<std::string, std::string>> security_properties(const SecurityFiles& files);

}  // namespace tessera::transport
