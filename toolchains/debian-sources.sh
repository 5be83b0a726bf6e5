#!/usr/bin/env bash
# Prints the apt sources the target sysroots and the package test's Debian roots are made
# from: one "deb URI SUITE COMPONENTS" line for each source this machine's apt uses for
# its own Debian suite (VERSION_CODENAME) and that suite's -updates and -security
# (apt-get indextargets; third-party repositories are left out). So every root comes
# from the same archive as the machine's own packages.
#
#   toolchains/debian-sources.sh            # the lines
#   toolchains/debian-sources.sh --suite    # only the suite's name
set -euo pipefail
# shellcheck source=/dev/null
suite=$(. /etc/os-release && echo "${VERSION_CODENAME:-}")
if [ -z "$suite" ]; then
  echo "debian-sources: error: no VERSION_CODENAME in /etc/os-release: cannot tell this machine's Debian suite" >&2
  exit 1
fi
if [ "${1:-}" = --suite ]; then
  echo "$suite"
  exit 0
fi
# shellcheck disable=SC2016 # apt's format, not the shell's
apt-get indextargets --format '$(REPO_URI) $(RELEASE) $(COMPONENT)' 'Identifier: Packages' |
  sort -u | awk -v s="$suite" '$2 == s || $2 == s "-updates" || $2 == s "-security" {
    key = $1 " " $2; if (!(key in c)) order[n++] = key; c[key] = c[key] " " $3 }
    END { for (i = 0; i < n; i++) print "deb " order[i] c[order[i]] }'
