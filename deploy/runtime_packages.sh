#!/usr/bin/env bash
# Prints, one per line and sorted, the Debian packages that hold the shared libraries the given
# binaries load (as ldd lists them, so indirect ones too). deploy/Dockerfile runs this in its
# build stage and installs exactly these packages in the runtime stage, so the runtime image
# follows whatever the binaries actually link instead of a hand-kept list.
#
#   bash deploy/runtime_packages.sh build/client/pdsm build/server/pdsm-coordinator ...
#
# Fails if a library cannot be found or belongs to no package (a library built by hand would
# be missing from the runtime image).
set -euo pipefail

if (($# == 0)); then
  echo "usage: $0 BINARY..." >&2
  exit 2
fi

# The package owning one library path. Debian 12 merged /lib into /usr/lib, but its dpkg
# database still records many libraries under /lib (and some under /usr/lib), while ldd prints
# whichever path the loader used, so try the path as printed, its target, and both spellings.
owner_of() {
  local lib=$1 candidate real
  real=$(readlink -f "$lib")
  for candidate in "$lib" "$real" "${lib#/usr}" "/usr${lib#/usr}" "${real#/usr}" "/usr${real#/usr}"; do
    # "libfoo1:amd64: /path" or "liba, libb: /path"; skip "diversion by ..." lines.
    if out=$(dpkg-query -S "$candidate" 2>/dev/null | grep -v '^diversion' | head -n 1) \
        && [[ -n $out ]]; then
      out=${out%%: /*}
      out=${out%%,*}
      echo "${out%%:*}"
      return 0
    fi
  done
  return 1
}

declare -A packages=()
status=0
for binary in "$@"; do
  if [[ ! -x $binary ]]; then
    echo "$0: $binary: not an executable file" >&2
    exit 1
  fi
  listing=$(ldd "$binary")
  if grep -q 'not found' <<<"$listing"; then
    echo "$listing" >&2
    echo "$0: $binary: some shared libraries were not found (above)" >&2
    exit 1
  fi
  # Lines "libfoo.so.1 => /path/libfoo.so.1 (0x...)" and the loader "/lib64/ld-linux... (0x...)";
  # linux-vdso has no file.
  while read -r lib; do
    [[ -n $lib ]] || continue
    if pkg=$(owner_of "$lib"); then
      packages[$pkg]=1
    else
      echo "$0: $binary: no Debian package holds $lib" >&2
      status=1
    fi
  done < <(awk '$2 == "=>" && $3 ~ /^\// { print $3 } $1 ~ /^\// { print $1 }' <<<"$listing")
done

((status == 0)) || exit "$status"
printf '%s\n' "${!packages[@]}" | sort
