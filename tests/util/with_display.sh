#!/bin/sh
# Runs a command under a virtual X display (xvfb-run -a) and exits with the command's own
# status. xvfb-run replaces that status with its own when removing its temporary directory
# fails (exit 5, "problem while cleaning up temporary directory", seen once in CI), so the
# command's status travels through a file instead.
#   tests/util/with_display.sh COMMAND [ARG...]
# HL_XVFB_SERVER_ARGS sets the server arguments (default: one 1280x1024x24 screen).
set -u
if [ "$#" -eq 0 ]; then
  echo "usage: with_display.sh COMMAND [ARG...]" >&2
  exit 2
fi
status_file=$(mktemp) || exit 1
xvfb-run -a -s "${HL_XVFB_SERVER_ARGS:--screen 0 1280x1024x24}" \
  sh -c '"$@"; s=$?; echo $s > "$0"; exit $s' "$status_file" "$@"
xvfb_status=$?
status=$(cat "$status_file")
rm -f "$status_file"
if [ -z "$status" ]; then
  echo "with_display.sh: xvfb-run exited $xvfb_status before the command finished" >&2
  exit "$xvfb_status"
fi
if [ "$xvfb_status" -ne "$status" ]; then
  echo "with_display.sh: xvfb-run exited $xvfb_status (its own clean-up); the command exited $status" >&2
fi
exit "$status"
