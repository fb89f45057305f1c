#!/usr/bin/env bash
# Makes everything `--security DIR` needs for a Tessera run with DDS Security: a test CA,
# one identity (EC P-256 key + certificate signed by the CA) per participant, and the
# governance and permissions documents signed by the CA (S/MIME, `openssl smime`).
#
#   scripts/security/make_identities.sh DIR N [options]
#       DIR    created if needed; must not already hold a CA (use a fresh folder)
#       N      number of agents: identities coordinator, agent_0 .. agent_(N-1)
#   options:
#       --ca-name NAME          common name of the CA (default "Tessera test CA")
#       --days D                validity of the certificates in days (default 3650)
#       --observer NAME         also an identity NAME allowed to SUBSCRIBE to Tessera's topics
#                               only (a read-only monitor)
#       --no-permission NAME    also an identity NAME signed by this CA whose permissions allow
#                               no Tessera topic (to test access control)
#
# Layout (docs/dds-runtime.md, "Security"):
#   DIR/ca_cert.pem             identity CA = permissions CA (public; every process reads it)
#   DIR/ca_key.pem              the CA's private key (keep it away from robots: only needed
#                               to add identities later)
#   DIR/governance.xml          domain rule: join access control, everything encrypted
#   DIR/governance.p7s          the same, signed by the CA (what the processes read)
#   DIR/<id>/cert.pem           identity certificate, subject "CN=<id>,O=Tessera"
#   DIR/<id>/key.pem            its private key (mode 600)
#   DIR/<id>/permissions.xml    what <id> may publish / subscribe (topics tessera_*)
#   DIR/<id>/permissions.p7s    the same, signed by the CA
# where <id> is "coordinator" or "agent_<k>". A process picks its own <id> from its role.
set -euo pipefail

die() { echo "make_identities.sh: $*" >&2; exit 2; }
command -v openssl >/dev/null || die "openssl is not installed (scripts/setup.sh installs it)"

[[ $# -ge 2 ]] || die "usage: make_identities.sh DIR N [--ca-name NAME] [--days D] [--observer NAME] [--no-permission NAME]"
dir=$1 n=$2
shift 2
[[ $n =~ ^[0-9]+$ && $n -ge 1 && $n -le 1000 ]] || die "N must be 1..1000, got '$n'"
ca_name="Tessera test CA" days=3650 observers=() outsiders=()
while [[ $# -gt 0 ]]; do
  case $1 in
    --ca-name) ca_name=${2:?--ca-name needs a value}; shift 2 ;;
    --days) days=${2:?--days needs a value}; shift 2 ;;
    --observer) observers+=("${2:?--observer needs a name}"); shift 2 ;;
    --no-permission) outsiders+=("${2:?--no-permission needs a name}"); shift 2 ;;
    *) die "unknown option $1" ;;
  esac
done
[[ $days =~ ^[0-9]+$ && $days -ge 1 ]] || die "--days must be a positive integer"
for name in "${observers[@]}" "${outsiders[@]}"; do
  [[ $name =~ ^[A-Za-z0-9_.-]+$ ]] || die "identity name '$name' may only hold [A-Za-z0-9_.-]"
done
mkdir -p "$dir"
[[ -e $dir/ca_key.pem ]] && die "$dir already holds a CA (ca_key.pem); use a fresh folder"
dir=$(cd "$dir" && pwd)
umask 077
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# The CA (EC P-256, self-signed). It also signs the S/MIME documents itself, so it needs
# digitalSignature: without it `PKCS7_verify` rejects them ("unsuitable certificate purpose").
openssl ecparam -name prime256v1 -genkey -noout -out "$dir/ca_key.pem"
openssl req -new -x509 -sha256 -days "$days" -key "$dir/ca_key.pem" -out "$dir/ca_cert.pem" \
  -subj "/O=Tessera/CN=$ca_name" \
  -addext "basicConstraints=critical,CA:TRUE" -addext "keyUsage=critical,keyCertSign,cRLSign,digitalSignature" 2>/dev/null
chmod 644 "$dir/ca_cert.pem"

sign() {  # sign IN.xml OUT.p7s: S/MIME signature by the CA, as the Access-Permissions plugin reads it
  openssl smime -sign -text -in "$1" -out "$2" -signer "$dir/ca_cert.pem" -inkey "$dir/ca_key.pem"
  chmod 644 "$1" "$2"
}

# Governance: only authenticated participants join (join access control), discovery,
# liveliness, RTPS messages, metadata and data are encrypted (AES-GCM) on every domain a run
# may use (0..232: the domain is derived from the run id unless given).
cat > "$dir/governance.xml" <<XML
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains>
        <id_range><min>0</min><max>232</max></id_range>
      </domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>ENCRYPT</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
XML
sign "$dir/governance.xml" "$dir/governance.p7s"

not_before=$(date -u +%Y-%m-%dT%H:%M:%S -d "-1 day")
not_after=$(date -u +%Y-%m-%dT%H:%M:%S -d "+$days days")

# identity ID MODE: key, certificate and signed permissions of one participant.
# MODE: full (publish + subscribe tessera_*), read (subscribe only), none (no Tessera topic).
identity() {
  local id=$1 mode=$2 d="$dir/$1"
  mkdir -p "$d"
  chmod 755 "$d"
  openssl ecparam -name prime256v1 -genkey -noout -out "$d/key.pem"
  openssl req -new -sha256 -key "$d/key.pem" -out "$tmp/$id.csr" -subj "/O=Tessera/CN=$id"
  openssl x509 -req -sha256 -days "$days" -in "$tmp/$id.csr" -CA "$dir/ca_cert.pem" \
    -CAkey "$dir/ca_key.pem" -set_serial "0x$(openssl rand -hex 8)" -out "$d/cert.pem" 2>/dev/null
  chmod 644 "$d/cert.pem"
  local topics="<topics><topic>tessera_*</topic></topics><partitions><partition>*</partition></partitions>"
  local rules
  case $mode in
    full) rules="<publish>$topics</publish><subscribe>$topics</subscribe>" ;;
    read) rules="<subscribe>$topics</subscribe>" ;;
    none) rules="<publish><topics><topic>not_tessera</topic></topics></publish>" ;;
  esac
  cat > "$d/permissions.xml" <<XML
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="$id">
      <subject_name>CN=$id,O=Tessera</subject_name>
      <validity>
        <not_before>$not_before</not_before>
        <not_after>$not_after</not_after>
      </validity>
      <allow_rule>
        <domains>
          <id_range><min>0</min><max>232</max></id_range>
        </domains>
        $rules
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
XML
  sign "$d/permissions.xml" "$d/permissions.p7s"
}

identity coordinator full
for ((k = 0; k < n; k++)); do identity "agent_$k" full; done
for name in "${observers[@]}"; do identity "$name" read; done
for name in "${outsiders[@]}"; do identity "$name" none; done
echo "make_identities.sh: CA '$ca_name' and $((n + 1 + ${#observers[@]} + ${#outsiders[@]})) identities in $dir"
