# Sourced by scripts that fetch a Debian source package: the mirrors come
# from the system's own apt configuration (a machine with its own mirror or
# proxy keeps using it), never from a host name written here.
#   debian_mirror archive    -> the URI serving the release itself (e.g. bookworm)
#   debian_mirror security   -> the URI serving <release>-security ("" if none)
# SLUICE_DEBIAN_MIRROR and SLUICE_DEBIAN_SECURITY_MIRROR override them.
debian_mirror() {
  local kind=${1:?usage: debian_mirror archive|security} override uri
  if [[ $kind == archive ]]; then override=${SLUICE_DEBIAN_MIRROR:-}; else override=${SLUICE_DEBIAN_SECURITY_MIRROR:-}; fi
  if [[ -n $override ]]; then echo "$override"; return; fi
  # Every binary index apt is configured for: "URI SUITE" (both list formats).
  uri=$(apt-get indextargets --format '$(REPO_URI) $(RELEASE) $(TARGET_OF)' 2>/dev/null | awk -v kind="$kind" '
    $3 != "deb" { next }
    kind == "security" && $2 ~ /-security$/ { print $1; exit }
    kind == "archive" && $2 !~ /-/ { print $1; exit }')
  if [[ -z $uri && $kind == archive ]]; then
    echo "error: apt has no Debian archive configured (looked in /etc/apt/sources.list and sources.list.d);" \
         "add one, or set SLUICE_DEBIAN_MIRROR=URI" >&2
    return 1
  fi
  echo "${uri%/}"
}

# deb-src lines for SUITES (e.g. "trixie trixie-updates") plus the matching
# -security suite where the system has a security mirror.
debian_source_list() {
  local release=${1:?usage: debian_source_list RELEASE} archive security
  archive=$(debian_mirror archive) || return 1
  security=$(debian_mirror security)
  echo "deb-src $archive $release main"
  echo "deb-src $archive $release-updates main"
  [[ -n $security ]] && echo "deb-src $security $release-security main"
  return 0
}
