#!/usr/bin/env bash
# Inputs that are not regular files (issue 18): for every reader path of the CLI (karst metrics on
# each survey format, --observed-table, compare --published and --survey, mesh), a FIFO (which
# blocked forever), /dev/zero behind the right name (which grew memory without bound) and a
# directory each end in exit 1, a message naming the file and what it is, and no output file
# created or replaced. Every run is under `timeout`, so a regression fails instead of hanging.
set -u
KARST=$1
SRC=$2
DATA=$SRC/datasets/surveys/karstnet
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
fail=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1"; fail=1; }
LIMIT=20 # seconds; each run takes milliseconds when the guard works

mkdir -p "$TMP/in" "$TMP/out"
# A small ensemble for compare (2 members, under a second).
timeout $LIMIT "$KARST" ensemble "$SRC/datasets/scenarios/branchwork.yaml" -n 2 -o "$TMP/ens" -q \
  >"$TMP/ens.log" 2>&1 || { bad "ensemble for compare"; cat "$TMP/ens.log"; }

# make KIND NAME: $TMP/in/KIND/NAME as a FIFO, a symlink to /dev/zero or a directory.
make_input() {
  local kind=$1 name=$2 p="$TMP/in/$1/$2"
  mkdir -p "$TMP/in/$kind"
  rm -rf "$p"
  case $kind in
    fifo) mkfifo "$p" ;;
    zero) ln -s /dev/zero "$p" ;;
    dir) mkdir "$p" ;;
  esac
  echo "$p"
}

# expect WHAT KIND PATH OUTFILE COMMAND...: exit 1 within the time limit, PATH and what it is in
# the message, OUTFILE (passed to -o by the command) neither created (FIFO, directory) nor replaced
# (/dev/zero, run with OUTFILE already there).
expect() {
  local what=$1 kind=$2 path=$3 out=$4; shift 4
  local want
  case $kind in
    fifo) want="is a FIFO (named pipe)" ;;
    zero) want="is a character device" ;;
    dir) want="is a directory" ;;
  esac
  # One run per case: a new output for FIFOs and directories, an existing one for /dev/zero.
  local mode=new
  [ $kind = zero ] && mode=existing
  for mode in $mode; do
    rm -f "$out"
    [ $mode = existing ] && echo sentinel >"$out"
    timeout $LIMIT "$@" >"$TMP/stdout" 2>"$TMP/stderr"
    local got=$?
    if [ $got != 1 ]; then
      bad "$what ($kind, output $mode): exit $got, expected 1"; cat "$TMP/stderr"; continue
    fi
    if ! grep -qF -- "$path: $want" "$TMP/stderr"; then
      bad "$what ($kind, output $mode): message lacks '$path: $want'"; cat "$TMP/stderr"; continue
    fi
    if [ $mode = new ] && [ -e "$out" ]; then bad "$what ($kind): $out was created"; continue; fi
    if [ $mode = existing ] && [ "$(cat "$out")" != sentinel ]; then
      bad "$what ($kind): $out was replaced"; continue
    fi
    if [ -n "$(ls -A "$TMP/out" | grep -v "^$(basename "$out")$")" ]; then
      bad "$what ($kind): stray files in the output directory: $(ls -A "$TMP/out")"; continue
    fi
    ok "$what ($kind, output $mode)"
  done
  rm -f "$out"
}

for kind in fifo zero dir; do
  # karst metrics on each survey and network format.
  for name in cave.vtp cave.3d cave.sql cave.pl cave.svx; do
    p=$(make_input $kind $name)
    expect "metrics $name" $kind "$p" "$TMP/out/m.csv" "$KARST" metrics "$p" -o "$TMP/out/m.csv"
  done
  # A Karstnet pair whose nodes file is hostile (the links file is a regular one).
  p=$(make_input $kind cave_nodes.dat)
  printf '1 2\n' >"$TMP/in/$kind/cave_links.dat"
  expect "metrics _nodes.dat" $kind "$p" "$TMP/out/m.csv" "$KARST" metrics "$p" -o "$TMP/out/m.csv"
  # The observed table of metrics --observed-table.
  p=$(make_input $kind observed.csv)
  expect "metrics --observed-table" $kind "$p" "$TMP/out/m.csv" \
    "$KARST" metrics "$DATA/Monachou.pl" --observed-table "$p" -o "$TMP/out/m.csv"
  # compare --published and compare --survey.
  p=$(make_input $kind published.csv)
  expect "compare --published" $kind "$p" "$TMP/out/c.csv" \
    "$KARST" compare "$TMP/ens" --published "$p" -o "$TMP/out/c.csv"
  for name in survey.vtp survey.3d; do
    p=$(make_input $kind $name)
    expect "compare --survey $name" $kind "$p" "$TMP/out/c.csv" \
      "$KARST" compare "$TMP/ens" --survey "$p" -o "$TMP/out/c.csv"
  done
  # mesh reads its network through the same readers.
  p=$(make_input $kind net.vtp)
  expect "mesh" $kind "$p" "$TMP/out/cave.ply" "$KARST" mesh "$p" -o "$TMP/out/cave.ply"
  # generate reads a scenario's point cloud (sampling.points) with the scenario.
  p=$(make_input $kind cloud.xyz)
  sed 's/^sampling:$/sampling:\n  points: cloud.xyz/' "$SRC/datasets/scenarios/branchwork.yaml" \
    >"$TMP/in/$kind/cloud.yaml"
  grep -q "points: cloud.xyz" "$TMP/in/$kind/cloud.yaml" || bad "cloud.yaml has no sampling.points"
  expect "generate sampling.points" $kind "$p" "$TMP/out/gen" \
    "$KARST" generate "$TMP/in/$kind/cloud.yaml" -o "$TMP/out/gen"
done

# refused WHAT OUT MESSAGE1 MESSAGE2 COMMAND...: exit 1 within the time limit, both messages
# (MESSAGE2 may be empty) in stderr, OUT not created.
refused() {
  local what=$1 out=$2 m1=$3 m2=$4; shift 4
  timeout $LIMIT "$@" >"$TMP/stdout" 2>"$TMP/stderr"
  local got=$?
  if [ $got = 1 ] && grep -qF -- "$m1" "$TMP/stderr" && { [ -z "$m2" ] || grep -qF -- "$m2" "$TMP/stderr"; } \
    && [ ! -e "$out" ]; then
    ok "$what"
  else
    bad "$what: exit $got"; cat "$TMP/stderr"
  fi
}

# A file within its type but over the size cap is refused before it is read: a sparse 600 MiB
# .pl (the survey cap is 512 MiB) costs no disk and no time.
truncate -s 600M "$TMP/in/big.pl"
refused "over the size cap" "$TMP/out/m.csv" \
  "$TMP/in/big.pl: the GOCAD PLine file is 629145600 bytes, more than the limit of 512 MiB" "" \
  "$KARST" metrics "$TMP/in/big.pl" -o "$TMP/out/m.csv"

# The same for a point cloud over its cap (1 GiB): a sparse 1.1 GiB cloud.xyz.
truncate -s 1100M "$TMP/in/dir/cloud.xyz.big"
rm -rf "$TMP/in/dir/cloud.xyz" && mv "$TMP/in/dir/cloud.xyz.big" "$TMP/in/dir/cloud.xyz"
refused "point cloud over the size cap" "$TMP/out/gen" \
  "$TMP/in/dir/cloud.xyz: the point cloud file is 1153433600 bytes, more than the limit of 1 GiB" \
  "(the points of sampling.points at $TMP/in/dir/cloud.yaml:" \
  "$KARST" generate "$TMP/in/dir/cloud.yaml" -o "$TMP/out/gen"

# An inf coordinate in an ASCII .vtp: the error names the file and the element.
cat >"$TMP/in/inf.vtp" <<'EOF'
<?xml version="1.0"?>
<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">
  <PolyData>
    <Piece NumberOfPoints="2" NumberOfLines="1">
      <Points>
        <DataArray type="Float64" Name="Points" NumberOfComponents="3" format="ascii">0 0 0 1 inf 2</DataArray>
      </Points>
      <Lines>
        <DataArray type="Int64" Name="connectivity" format="ascii">0 1</DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii">2</DataArray>
      </Lines>
    </Piece>
  </PolyData>
</VTKFile>
EOF
refused "inf coordinate" "$TMP/out/m.csv" "$TMP/in/inf.vtp: <DataArray Name=\"Points\"> at byte" \
  "value 4 ('inf') is not a finite number" "$KARST" metrics "$TMP/in/inf.vtp" -o "$TMP/out/m.csv"
# The same file with the coordinate repaired loads (the check is not what failed above).
sed -i 's/1 inf 2/1 1 2/' "$TMP/in/inf.vtp"
timeout $LIMIT "$KARST" metrics "$TMP/in/inf.vtp" --format csv >"$TMP/stdout" 2>"$TMP/stderr" \
  && ok "repaired file loads" || { bad "repaired file"; cat "$TMP/stderr"; }
exit $fail
