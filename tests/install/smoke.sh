#!/usr/bin/env bash
# make test-install: the .deb of `make package` unpacked into an empty directory (dpkg-deb -x,
# which leaves the machine's dpkg database alone) works from there, holds every file at the path
# Debian's tools look in, and depends on the packages whose libraries dfp-sim loads; then
# `cmake --install --prefix DIR` (make install) gives a working dfp-sim as well.
# Usage: smoke.sh BUILD_DIR DEB
build=$1
deb=$2
here=$(cd "$(dirname "$0")" && pwd)
. "$here/../cli/lib.sh"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
start=$EPOCHREALTIME
root=$tmp/root
mkdir -p "$root"

if [ -f "$deb" ]; then ok; else bad "no package at $deb"; echo "$passed passed, $failed failed"; exit 1; fi
version=$("$build/sim_host/dfp_sim/dfp-sim" --version)
project_version=$(sed -n 's/^CMAKE_PROJECT_VERSION:STATIC=//p' "$build/CMakeCache.txt")
for field in "Package=dfp21b-sim" "Version=$project_version" "Architecture=$(dpkg --print-architecture)"; do
  got=$(dpkg-deb -f "$deb" "${field%%=*}")
  if [ "$got" = "${field#*=}" ]; then ok; else bad "package ${field%%=*} is '$got', expected '${field#*=}'"; fi
done

# The files, at the paths Debian's man, bash-completion, zsh, Wireshark and python3 look in.
multiarch=$(dpkg-architecture -qDEB_HOST_MULTIARCH 2>/dev/null || gcc -print-multiarch)
lua_dir=usr/lib/$multiarch/wireshark/plugins
listing=$(dpkg -c "$deb" | awk '{print $6}')
for path in usr/bin/dfp-sim usr/share/man/man1/dfp-sim.1.gz \
    usr/share/bash-completion/completions/dfp-sim usr/share/zsh/vendor-completions/_dfp-sim \
    usr/share/dfp21b/gsd/SEW_6003.GSD usr/share/dfp21b/gsd/SEWA6003.GSD \
    "$lua_dir/dfp21b/profibus.lua" "$lua_dir/dfp21b/profibus_names.lua" \
    "$lua_dir/dfp21b/profibus_fields.lua" "$lua_dir/dfp21b/profibus_dpv0.lua" \
    "$lua_dir/dfp21b/profibus_dpv1.lua" "$lua_dir/dfp21b/movidrive_params.lua" \
    usr/lib/python3/dist-packages/dfpsim/__init__.py usr/lib/python3/dist-packages/dfpsim/client.py; do
  if grep -qxF "./$path" <<<"$listing"; then ok; else bad "dpkg -c: no ./$path"; fi
done
outside=$(grep -v '^\./$' <<<"$listing" | grep -v '^\./usr/' || true)
if [ -z "$outside" ]; then ok; else bad "files outside /usr: $outside"; fi
if grep -q '__pycache__\|\.pyc$' <<<"$listing"; then bad "byte code in the package"; else ok; fi
if command -v tshark >/dev/null; then
  global_lua=$(tshark -G folders 2>/dev/null | sed -n 's/^Global Lua Plugins:[[:space:]]*//p')
  if [ "$global_lua" = "/$lua_dir" ]; then ok; else bad "tshark's global Lua plugin folder is '$global_lua', the package uses /$lua_dir"; fi
fi

# Depends names the package of every library dfp-sim needs (its NEEDED entries, resolved by ldd).
dpkg-deb -x "$deb" "$root"
sim=$root/usr/bin/dfp-sim
depends=$(dpkg-deb -f "$deb" Depends)
echo "Depends: $depends"
libs=$(ldd "$sim")
if grep -q "not found" <<<"$libs"; then bad "ldd: $(grep "not found" <<<"$libs")"; else ok; fi
needed=$(readelf -d "$sim" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')
for so in $needed; do
  path=$(awk -v so="$so" '$1 == so && $3 ~ /^\// {print $3}' <<<"$libs")
  pkg=$(dpkg -S "$(readlink -f "$path")" 2>/dev/null | head -n1 | cut -d: -f1)
  [ -z "$pkg" ] && pkg=$(dpkg -S "$path" 2>/dev/null | head -n1 | cut -d: -f1)
  if [ -n "$pkg" ] && grep -qE "(^|, )$pkg( |,|$)" <<<"$depends"; then ok; else bad "$so ($path, package '$pkg') is not in Depends: $depends"; fi
done
if command -v apt-get >/dev/null; then
  sim_apt=$(apt-get -s install "$(readlink -f "$deb")" 2>&1)
  expect_in "apt-get -s install resolves it" "Inst dfp21b-sim" "$sim_apt"
fi

# Run from the unpacked tree, outside the build and without LD_LIBRARY_PATH.
expect_exit 0 "installed --version" -- env -u LD_LIBRARY_PATH "$sim" --version
if [ "$out" = "$version" ]; then ok; else bad "installed --version '$out', built '$version'"; fi
echo "$out"
(cd "$tmp" && env -u LD_LIBRARY_PATH "$sim" demo --capture "$tmp/demo.pcap" --capture-linktype user0 >"$tmp/demo.txt" 2>&1)
rc=$?
if [ $rc = 0 ]; then ok; else bad "installed demo: exit $rc"; fi
verdict=$(grep "result:" "$tmp/demo.txt")
expect_in "installed demo's verdict" "result: every scene behaved as the manual describes" "$verdict"
echo "demo: $(sed 's/^ *//' <<<"$verdict")"

man_src=$(gzip -dc "$root/usr/share/man/man1/dfp-sim.1.gz")
if [ "$man_src" = "$("$sim" --man)" ]; then ok; else bad "the packaged man page is not what --man prints"; fi
if command -v man >/dev/null; then
  rendered=$(MANWIDTH=100 man -l "$root/usr/share/man/man1/dfp-sim.1.gz" 2>&1 | col -bx)
  expect_in "man shows EXIT STATUS" "EXIT STATUS" "$rendered"
fi
for f in SEW_6003.GSD SEWA6003.GSD; do
  if cmp -s "$here/../../firmware/gsd/$f" "$root/usr/share/dfp21b/gsd/$f"; then ok; else bad "$f differs"; fi
done

# The packaged completions, with the packaged binary (tests/cli/test_completion.sh).
comp_out=$(bash "$here/../cli/test_completion.sh" "$sim" "$root/usr/share/bash-completion/completions/dfp-sim" \
  "$root/usr/share/zsh/vendor-completions/_dfp-sim" 2>&1)
if [ $? = 0 ]; then ok; else bad "completions: $comp_out"; fi
echo "completions: $(tail -n1 <<<"$comp_out")"

# The Python client on python3's path from dist-packages, the dissector as Wireshark loads it
# from a plugin folder (a personal one pointing at the packaged files).
if [ -x /usr/bin/python3 ]; then
  on_path=$(/usr/bin/python3 -c 'import sys; print("/usr/lib/python3/dist-packages" in sys.path)')
  if [ "$on_path" = True ]; then ok; else bad "/usr/lib/python3/dist-packages is not on Debian's python3 path"; fi
fi
py=$(PYTHONPATH=$root/usr/lib/python3/dist-packages python3 -c 'import dfpsim; print(dfpsim.__file__, hasattr(dfpsim, "DfpSim"))' 2>&1)
if [ "$py" = "$root/usr/lib/python3/dist-packages/dfpsim/__init__.py True" ]; then ok; else bad "import dfpsim: $py"; fi
if command -v tshark >/dev/null; then
  mkdir -p "$tmp/home/.local/lib/wireshark"
  ln -s "$root/$lua_dir" "$tmp/home/.local/lib/wireshark/plugins"
  decoded=$(HOME=$tmp/home tshark -r "$tmp/demo.pcap" 2>/dev/null)
  n=$(grep -c "Data_Exchange 14 octets ML read 8300 (P076 firmware basic unit)" <<<"$decoded")
  if [ "$n" -gt 0 ]; then ok; else bad "tshark with the packaged dissector: $(head -n3 <<<"$decoded")"; fi
  echo "tshark with the packaged dissector: $(wc -l <<<"$decoded") telegrams, $n MOVILINK reads of P076"
fi

# make install PREFIX=DIR
prefix=$tmp/prefix
cmake --install "$build" --prefix "$prefix" >"$tmp/install.log" 2>&1 || bad "cmake --install: $(tail -n3 "$tmp/install.log")"
expect_exit 0 "PREFIX/bin/dfp-sim --version" -- "$prefix/bin/dfp-sim" --version
if [ "$out" = "$version" ]; then ok; else bad "PREFIX/bin/dfp-sim --version '$out'"; fi
for path in share/man/man1/dfp-sim.1.gz share/bash-completion/completions/dfp-sim \
    share/zsh/vendor-completions/_dfp-sim share/dfp21b/gsd/SEW_6003.GSD "$lua_dir/dfp21b/profibus.lua" \
    lib/python3/dist-packages/dfpsim/__init__.py; do
  path=${path#usr/}
  if [ -f "$prefix/$path" ]; then ok; else bad "make install: no PREFIX/$path"; fi
done
echo "make install PREFIX=...: $(find "$prefix" -type f | wc -l) files"

echo "test-install: $(awk -v a="$start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.1f", b - a }') s"
finish
