#!/bin/bash
# The container's health: rmapd answers GET /healthz with status ok. Bash's /dev/tcp, so the
# image needs no curl. RMAP_PORT: the port of the config's `listen` (8080 in the image's).
set -u
exec 3<>"/dev/tcp/127.0.0.1/${RMAP_PORT:-8080}" || exit 1
printf 'GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n' >&3
grep -q '"status":"ok"' <&3
