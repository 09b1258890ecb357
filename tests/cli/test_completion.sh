#!/usr/bin/env bash
# The bash completion and the man page are generated from the command table, the table behind
# `karst --help` and `karst help COMMAND`: the completion is exercised in bash itself (the
# COMPREPLY that the completion function returns for typed words), the man page rendered by
# man-db's `man -l`; both are compared with the help texts and with the files the build
# generated for `cmake --install` (karst.1, karst.bash beside the binary).
set -u
KARST=$1
SRC=$2
BUILD=$(cd "$(dirname "$KARST")" && pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

"$KARST" completion bash >"$T/karst.bash" || fail "karst completion bash"
cmp -s "$T/karst.bash" "$BUILD/karst.bash" || fail "the built karst.bash differs from 'karst completion bash'"
bash -n "$T/karst.bash" || fail "the completion script is not valid bash"
commands=$("$KARST" --help | sed -n 's/^  \([a-z]*\) .*/\1/p')
[ -n "$commands" ] || fail "no commands in --help"

# complete WORD... : what bash offers for the last word (the one being completed).
complete_words() {
  (cd "$T/files" && bash -c '
    source "$1"; shift
    COMP_WORDS=(karst "$@"); COMP_CWORD=$#
    _karst
    printf "%s\n" "${COMPREPLY[@]}" | sort' _ "$T/karst.bash" "$@")
}
mkdir -p "$T/files/sub" && touch "$T/files/a.yaml" "$T/files/b.txt" "$T/files/c.vtp"
expect() { # "expected words" word...
  local want=$1; shift
  local got
  got=$(complete_words "$@" | tr '\n' ' ' | sed 's/ $//')
  [ "$got" = "$want" ] || fail "karst $* <TAB>: got '$got', expected '$want'"
  echo "ok: karst $* <TAB> -> $want"
}
expect "generate" ge
expect "compare completion" comp
expect "--samples --seed" generate x.yaml --s
expect "csv json table" metrics --format ""
expect "csv" metrics x.vtp --format c
expect "a.yaml sub" generate ""
expect "sub" ensemble a.yaml -o ""
expect "a.yaml sub" mesh c.vtp --scenario ""
expect "c.vtp sub" mesh ""
expect "" generate a.yaml --seed ""
expect "bash" completion ""
expect "$(printf '%s\n' $commands help | sort | tr '\n' ' ' | sed 's/ $//')" help ""
expect "--crs" export sub --c
expect "--qml --quiet" export sub --q
# Every option of every command's synopsis is offered after '-'.
for c in $commands; do
  offered=" $(complete_words "$c" - | tr '\n' ' ')"
  for o in $("$KARST" help "$c" | sed -n '/^usage:/,/^$/p' | grep -o -- '[[ ]-[-a-zA-Z]*' | tr -d '[ '); do
    case "$offered" in *" $o "*) ;; *) fail "karst $c -<TAB> does not offer $o (offered:$offered)" ;; esac
  done
done
echo "ok: every synopsis option of every command is completed"

# The man page: the build's karst.1 is 'karst help --man'; man renders it without warnings, and
# each command's help text appears in it line by line.
"$KARST" help --man >"$T/karst.1" || fail "karst help --man"
cmp -s "$T/karst.1" "$BUILD/karst.1" || fail "the built karst.1 differs from 'karst help --man'"
command -v man >/dev/null || fail "man is required (scripts/install-deps installs man-db)"
LC_ALL=C.UTF-8 MANWIDTH=200 man --warnings -E utf-8 -l "$T/karst.1" >"$T/man.txt" 2>"$T/warn.txt" \
  || fail "man -l karst.1"
[ -s "$T/warn.txt" ] && { cat "$T/warn.txt"; fail "man reports warnings"; }
grep -q "^KARST(1)" "$T/man.txt" || fail "no KARST(1) header"
sed 's/^ *//; s/ *$//' "$T/man.txt" >"$T/man.stripped"
for c in help $commands; do
  grep -qx "karst $c" "$T/man.stripped" || fail "no section for karst $c"
  "$KARST" help "$c" | tail -n +3 | sed 's/^ *//; s/ *$//' | grep -v '^$' | while IFS= read -r line; do
    grep -qxF -- "$line" "$T/man.stripped" || { echo "FAIL: man page lacks, for $c: '$line'"; exit 1; }
  done || exit 1
done
echo "ok: the man page holds every command's help, line by line"
