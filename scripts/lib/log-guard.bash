# Sourced by scripts/test: the user's layer log folder, read before and after the tests, so a
# test that writes there (where an app run meanwhile would too) fails the run. A fresh machine
# has no such folder yet: that reads as an empty listing, not as an error under `set -e` and
# `pipefail`. tests/fresh_machine.rs runs this against new empty XDG folders.
#   user_log_folder    where the layer logs for this user (XDG_STATE_HOME or ~/.local/state)
#   log_listing        one line per file there: path, size, modification time; sorted

user_log_folder() { echo "${XDG_STATE_HOME:-$HOME/.local/state}/contrastxr"; }

log_listing() {
  local dir
  dir="$(user_log_folder)"
  [ -d "$dir" ] || return 0
  find "$dir" -printf '%P %s %T@\n' | sort
}
