#!/usr/bin/env bash
# A private certificate authority and a broker certificate for the fleet's Mosquitto:
#   toolchain/broker-pki.sh DIR [HOSTNAME...]
# writes DIR/ca.crt (give it to every robot and the centre: fleet.ca_file), DIR/ca.key (keep it
# offline), DIR/server.crt and DIR/server.key (the broker's). The certificate names every
# HOSTNAME (default: localhost) and 127.0.0.1. Keys are P-256 EC.
set -euo pipefail
if [[ $# -lt 1 ]]; then
  echo "usage: $0 DIR [HOSTNAME...]" >&2
  exit 2
fi
dir=$1
shift
hosts=("$@")
[[ ${#hosts[@]} -gt 0 ]] || hosts=(localhost)
command -v openssl >/dev/null || { echo "broker-pki.sh: needs openssl" >&2; exit 1; }
mkdir -p "$dir"
umask 077
san="subjectAltName=IP:127.0.0.1"
for host in "${hosts[@]}"; do san+=",DNS:${host}"; done
openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 3650 \
  -subj "/CN=Sen3Bot fleet CA" -keyout "$dir/ca.key" -out "$dir/ca.crt" 2>/dev/null
openssl req -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes \
  -subj "/CN=${hosts[0]}" -keyout "$dir/server.key" -out "$dir/server.csr" 2>/dev/null
openssl x509 -req -in "$dir/server.csr" -CA "$dir/ca.crt" -CAkey "$dir/ca.key" -CAcreateserial \
  -days 825 -extfile <(printf '%s\n' "$san") -out "$dir/server.crt" 2>/dev/null
rm -f "$dir/server.csr" "$dir/ca.srl"
chmod 644 "$dir/ca.crt" "$dir/server.crt"
echo "broker-pki.sh: CA and broker certificate for ${hosts[*]} in $dir"
