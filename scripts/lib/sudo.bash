# Sourced by the scripts that run as root (scripts/test, scripts/demo). Under sudo, which resets
# PATH, cargo is taken from the invoking user's rustup install; and when the script ends, what
# the run wrote as root into the checkout and that user's cargo folders goes back to the user, so
# their next build as themselves does not fail on root-owned files.
#   needs_cargo NAME   exit at once, with the command to run, when there is no cargo
#   give_back          chown what root wrote back to $SUDO_USER (nothing without sudo); call it
#                      from the script's EXIT trap

sudo_user_dirs=()
if [ -n "${SUDO_USER:-}" ] && [ "$(id -u)" -eq 0 ] && ! command -v cargo >/dev/null; then
  sudo_home="$(getent passwd "$SUDO_USER" | cut -d: -f6)"
  if [ -x "$sudo_home/.cargo/bin/cargo" ]; then
    export PATH="$sudo_home/.cargo/bin:$PATH"
    export CARGO_HOME="$sudo_home/.cargo" RUSTUP_HOME="$sudo_home/.rustup"
    sudo_user_dirs=("$CARGO_HOME" "$RUSTUP_HOME")
  fi
fi

needs_cargo() {
  command -v cargo >/dev/null && return 0
  if [ -n "${SUDO_USER:-}" ]; then
    echo "$1: cargo is neither on root's PATH nor in ~$SUDO_USER/.cargo/bin: from your shell, where cargo works, run \`sudo env PATH=\"\$PATH\" CARGO_HOME=\"\${CARGO_HOME:-\$HOME/.cargo}\" RUSTUP_HOME=\"\${RUSTUP_HOME:-\$HOME/.rustup}\" $0\`" >&2
  else
    echo "$1: cargo is not on PATH: install Rust with rustup (https://rustup.rs), then run this again" >&2
  fi
  exit 1
}

give_back() {
  [ -n "${SUDO_UID:-}" ] && [ "$SUDO_UID" != 0 ] && [ "$(id -u)" -eq 0 ] || return 0
  local dirs=("$PWD" "${sudo_user_dirs[@]}")
  find "${dirs[@]}" -xdev -user 0 -exec chown -h "$SUDO_UID:$SUDO_GID" {} + 2>/dev/null || true
}
