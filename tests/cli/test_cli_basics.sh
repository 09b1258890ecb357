#!/usr/bin/env bash
# The command-line contract: help, version, exit codes 0 / 1 / 2.
set -u
KARST=$1
fail=0
check() { # expected-exit description command...
  local want=$1 what=$2; shift 2
  "$@" >/tmp/karst_cli_out.$$ 2>&1; local got=$?
  if [ "$got" != "$want" ]; then echo "FAIL: $what: exit $got, expected $want"; cat /tmp/karst_cli_out.$$; fail=1; else echo "ok: $what"; fi
}
check 0 "--help" "$KARST" --help
check 0 "--version" "$KARST" --version
"$KARST" --version | head -n 1 | grep -Eq '^karst [0-9]+\.[0-9]+\.[0-9]+$' || { echo "FAIL: version format"; fail=1; }
check 0 "help validate" "$KARST" help validate
"$KARST" help validate | grep -q "FILE:LINE:COLUMN" || { echo "FAIL: help validate text"; fail=1; }
check 2 "no command" "$KARST"
check 2 "unknown command" "$KARST" frobnicate
check 2 "help unknown" "$KARST" help frobnicate
check 2 "unknown global option" "$KARST" --bogus
grep -q "^karst: unknown option '--bogus'.*See 'karst --help'" /tmp/karst_cli_out.$$ \
  || { echo "FAIL: --bogus message"; cat /tmp/karst_cli_out.$$; fail=1; }
"$KARST" frobnicate 2>&1 | grep -q "^karst: 'frobnicate' is not a karst command. See 'karst --help'" \
  || { echo "FAIL: unknown command message"; fail=1; }
# Unknown options of each command: exit 2, the option named, a hint to the help.
for c in validate generate metrics ensemble compare report mesh; do
  check 2 "$c --bogus" "$KARST" $c --bogus x
  grep -q "^karst $c: unknown option.*'--bogus'" /tmp/karst_cli_out.$$ \
    || { echo "FAIL: $c --bogus message"; cat /tmp/karst_cli_out.$$; fail=1; }
  grep -q "^Run 'karst help $c' for its options, 'karst --help' for the commands.$" /tmp/karst_cli_out.$$ \
    || { echo "FAIL: $c --bogus hint"; cat /tmp/karst_cli_out.$$; fail=1; }
done
check 2 "validate without file" "$KARST" validate
check 2 "validate bad option" "$KARST" validate --frob x.yaml
check 1 "validate missing file" "$KARST" validate /nonexistent/scenario.yaml
# --seed out of range or not a number: a usage error naming the option (before any file is read).
for s in -1 18446744073709551616 abc 1e3 " 5"; do
  check 2 "generate --seed '$s'" "$KARST" generate /nonexistent.yaml -o /tmp/none --seed "$s"
  grep -q "^karst generate: --seed must be an integer from 0 to 18446744073709551615, got '$s'" \
    /tmp/karst_cli_out.$$ || { echo "FAIL: --seed '$s' message"; cat /tmp/karst_cli_out.$$; fail=1; }
  check 2 "ensemble --seed '$s'" "$KARST" ensemble /nonexistent.yaml -n 1 -o /tmp/none --seed "$s"
done
for c in validate generate metrics ensemble compare report mesh; do
  "$KARST" --help | grep -q "^  $c " || { echo "FAIL: $c not listed in --help"; fail=1; }
done
rm -f /tmp/karst_cli_out.$$
exit $fail
