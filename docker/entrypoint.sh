#!/bin/sh
# Starts rmapd with the image's config (RMAP_CONFIG, default /etc/rmap/rmapd.yaml) plus tokens
# from the environment: off loopback rmapd serves only clients with a token (docs/API.md §3).
#   RMAP_ADMIN_TOKEN, RMAP_VIEWER_TOKEN  one token each (8 characters or more)
#   RMAP_ROBOT_TOKENS                    robot_id=token pairs, comma-separated
# Arguments are passed on to rmapd (they override the config, e.g. --log-level debug).
set -eu
config=${RMAP_CONFIG:-/etc/rmap/rmapd.yaml}

if [ -z "${RMAP_ADMIN_TOKEN:-}${RMAP_VIEWER_TOKEN:-}${RMAP_ROBOT_TOKENS:-}" ]; then
  grep -q '^auth:' "$config" ||
    echo "rmapd-entrypoint: no tokens (set RMAP_ADMIN_TOKEN, RMAP_VIEWER_TOKEN or RMAP_ROBOT_TOKENS):" \
         "rmapd refuses every client that is not on this container's loopback" >&2
  exec rmapd --config "$config" "$@"
fi
if grep -q '^auth:' "$config"; then
  echo "rmapd-entrypoint: $config has an auth section; give the tokens there or in the environment, not both" >&2
  exit 2
fi

# A YAML single-quoted scalar: quotes doubled.
quote() { printf "'%s'" "$(printf '%s' "$1" | sed "s/'/''/g")"; }

generated=$(mktemp "${TMPDIR:-/tmp}/rmapd-XXXXXX.yaml")  # 0600: the tokens stay the user's
{
  cat "$config"
  echo
  echo "auth:"
  echo "  tokens:"
  if [ -n "${RMAP_ADMIN_TOKEN:-}" ]; then echo "    - {token: $(quote "$RMAP_ADMIN_TOKEN"), role: admin}"; fi
  if [ -n "${RMAP_VIEWER_TOKEN:-}" ]; then echo "    - {token: $(quote "$RMAP_VIEWER_TOKEN"), role: viewer}"; fi
  old_ifs=$IFS
  IFS=,
  for pair in ${RMAP_ROBOT_TOKENS:-}; do
    case "$pair" in
      ?*=?*) ;;
      *) echo "rmapd-entrypoint: RMAP_ROBOT_TOKENS must be robot_id=token pairs separated by commas, not '$pair'" >&2
         exit 2 ;;
    esac
    echo "    - {token: $(quote "${pair#*=}"), role: robot, robot_id: $(quote "${pair%%=*}")}"
  done
  IFS=$old_ifs
} >"$generated"
exec rmapd --config "$generated" "$@"
