# Sourced by the ensure-*.sh scripts: `apt_install WHAT PACKAGE...` installs Debian packages as root
# or through sudo, or fails naming WHAT it could not install.
apt_install() {
  local what=$1; shift
  local sudo=""
  if [ "$(id -u)" != 0 ]; then
    command -v sudo >/dev/null || { echo "error: need root or sudo to install $what ($*)" >&2; return 1; }
    sudo="sudo"
  fi
  echo "Installing $what..." >&2
  $sudo apt-get update -qq
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "$@" >/dev/null
}
