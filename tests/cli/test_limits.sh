#!/usr/bin/env bash
# Resource limits and lost output (issue 18, items 3, 4, 7) through the real binary: absurd
# scenarios refused by validate and generate at FILE:LINE:COLUMN with nothing written,
# --max-memory, --threads bounds, write errors on standard output, -o naming an input, and the
# lock of generate's directory. Expected positions are those of the values in the fixture files
# (tests/data/scenarios/limits/*.yaml: line 1 a comment, the key's value on line 11).
set -u
KARST=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
SRC=$(cd "$2" && pwd)
LIM=$SRC/tests/data/scenarios/limits
MIN=$SRC/tests/data/scenarios/good/minimal.yaml
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
run() { # expected-exit description command... (stdout -> $tmp/out, stderr -> $tmp/err)
  local want=$1 what=$2; shift 2
  "$@" >"$tmp/out" 2>"$tmp/err"; local got=$?
  if [ "$got" != "$want" ]; then
    echo "FAIL: $what: exit $got, expected $want"; cat "$tmp/out" "$tmp/err"; fail=1
  else
    echo "ok: $what"
  fi
}
err_has() { # the stderr of the last run contains this text
  grep -qF -- "$1" "$tmp/err" || { echo "FAIL: stderr lacks '$1': $(cat "$tmp/err")"; fail=1; }
}

# The six absurd scenarios: refused by validate and by generate (nothing written), each at the
# position of the key behind the refusal.
for case in "amplification_points:11:3:more than 1000000" \
            "amplification_steps:11:10:amplification.steps is 1000000, more than 1000" \
            "feature_radius:11:19:at sampling.feature_radius 1e-09 m needs up to" \
            "huge_domain:3:3:needs up to inf samples" \
            "max_samples:11:16:sampling.max_samples: the run needs an estimated" \
            "sampling_k:11:6:sampling.k: the run needs an estimated"; do
  name=${case%%:*}; rest=${case#*:}; line=${rest%%:*}; rest=${rest#*:}; col=${rest%%:*}
  msg=${rest#*:}
  run 1 "validate refuses $name" timeout 20 "$KARST" validate "$LIM/$name.yaml"
  err_has "$LIM/$name.yaml:$line:$col: "
  err_has "$msg"
  run 1 "generate refuses $name" timeout 20 "$KARST" generate "$LIM/$name.yaml" -o "$tmp/g_$name"
  err_has "$LIM/$name.yaml:$line:$col: "
  [ -e "$tmp/g_$name" ] && { echo "FAIL: generate $name wrote $tmp/g_$name"; fail=1; }
done

# --max-memory: 1M refuses a shipped preset (the estimate and the limit in human units), a
# large value accepts it.
P=$SRC/datasets/scenarios/gorge.yaml
run 1 "validate --max-memory 1M refuses gorge" "$KARST" validate --max-memory 1M "$P"
err_has "more than the limit of 1 MiB (--max-memory)"
run 1 "generate --max-memory 1M refuses gorge" "$KARST" generate "$P" --max-memory 1M -o "$tmp/gm"
[ -e "$tmp/gm" ] && { echo "FAIL: generate --max-memory 1M wrote $tmp/gm"; fail=1; }
run 1 "ensemble --max-memory 1M refuses gorge" "$KARST" ensemble "$P" -n 2 --max-memory 1M -o "$tmp/em" -q
err_has "more than the limit of 1 MiB"
[ -e "$tmp/em" ] && { echo "FAIL: ensemble --max-memory 1M wrote $tmp/em"; fail=1; }
run 0 "validate --max-memory 64G accepts gorge" "$KARST" validate --max-memory 64G "$P"
grep -q "of memory" "$tmp/out" || { echo "FAIL: no estimate in the summary"; fail=1; }
run 2 "--max-memory needs a size" "$KARST" validate --max-memory lots "$P"

# --threads is bounded as -j is.
for cmd in generate mesh metrics blocks; do
  run 2 "$cmd --threads 100000" "$KARST" $cmd --threads 100000 x -o "$tmp/t_$cmd"
  err_has "within [1, 1024], got '100000'"
done

# A write error on standard output is an error.
run 0 "generate minimal" "$KARST" generate "$MIN" -o "$tmp/net" --quiet
run 1 "metrics > /dev/full" sh -c "'$KARST' metrics '$tmp/net/network.vtp' > /dev/full"
err_has "karst metrics: writing standard output"
run 1 "validate > /dev/full" sh -c "'$KARST' validate '$MIN' > /dev/full"
err_has "karst validate: writing standard output"
run 0 "ensemble of 3" "$KARST" ensemble "$MIN" -n 3 -o "$tmp/ens" -j 1 --seed 4 -q
run 1 "compare > /dev/full" sh -c "'$KARST' compare '$tmp/ens' > /dev/full"
err_has "karst compare: writing standard output"
run 1 "help > /dev/full" sh -c "'$KARST' help generate > /dev/full"
run 1 "--version > /dev/full" sh -c "'$KARST' --version > /dev/full"
run 1 "generate --help > /dev/full" sh -c "'$KARST' generate --help > /dev/full"

# -o naming an input is refused before any work (exit 2, as a usage error), the input unchanged;
# a symlink and a ./path name the same file.
cp "$tmp/net/network.vtp" "$tmp/in.vtp"
sum=$(cksum < "$tmp/in.vtp")
ln -s "$tmp/in.vtp" "$tmp/link.vtp"
run 2 "metrics -o IN" "$KARST" metrics "$tmp/in.vtp" -o "$tmp/in.vtp"
err_has "is the input"
run 2 "metrics -o symlink to IN" "$KARST" metrics "$tmp/in.vtp" -o "$tmp/link.vtp"
run 2 "mesh -o IN" "$KARST" mesh "$tmp/in.vtp" -o "$tmp/in.vtp"
err_has "is the input"
(cd "$tmp" && run 2 "mesh -o ./IN" "$KARST" mesh in.vtp -o ./in.vtp)
[ "$(cksum < "$tmp/in.vtp")" = "$sum" ] || { echo "FAIL: the input was changed"; fail=1; }
[ -e "$tmp/in.paraview.py" ] && { echo "FAIL: mesh wrote its script"; fail=1; }
sum=$(cksum < "$tmp/ens/metrics.csv")
run 2 "compare -o the ensemble's metrics.csv" "$KARST" compare "$tmp/ens" -o "$tmp/ens/metrics.csv"
err_has "is the input"
[ "$(cksum < "$tmp/ens/metrics.csv")" = "$sum" ] || { echo "FAIL: metrics.csv was changed"; fail=1; }
# mesh --scenario: -o naming a file the scenario reads (its terrain surface) is refused too.
mkdir "$tmp/sc"
printf 'domain:\n  min: [0, 0, 0]\n  max: [100, 100, 50]\nterrain:\n  heightfield: hill.asc\nkey_points:\n  - {type: sink, position: [10, 10, 40]}\n  - {type: spring, position: [90, 90, 10]}\n' > "$tmp/sc/s.yaml"
printf 'ncols 3\nnrows 3\nxllcorner -50\nyllcorner -50\ncellsize 100\nNODATA_value -9999\n50 50 50\n50 50 50\n50 50 50\n' > "$tmp/sc/hill.asc"
ln -s hill.asc "$tmp/sc/hill.vtp"  # a name mesh accepts, for the scenario's file
sum=$(cksum < "$tmp/sc/hill.asc")
run 0 "the heightfield scenario validates" "$KARST" validate "$tmp/sc/s.yaml"
run 2 "mesh -o a file the scenario reads" "$KARST" mesh "$tmp/in.vtp" --scenario "$tmp/sc/s.yaml" -o "$tmp/sc/hill.vtp"
err_has "is the input $tmp/sc/hill.asc"
[ "$(cksum < "$tmp/sc/hill.asc")" = "$sum" ] || { echo "FAIL: the heightfield was changed"; fail=1; }
# export: neither the GeoPackage nor its style may replace what it reads (DIR/run.json here).
sum=$(cksum < "$tmp/net/run.json")
run 2 "export --qml DIR/run.json" "$KARST" export "$tmp/net" --gpkg "$tmp/x.gpkg" --qml "$tmp/net/run.json"
err_has "is the input $tmp/net/run.json"
[ "$(cksum < "$tmp/net/run.json")" = "$sum" ] || { echo "FAIL: export changed run.json"; fail=1; }
[ -e "$tmp/x.gpkg" ] && { echo "FAIL: export wrote its GeoPackage"; fail=1; }
# blocks: no output may replace a file the scenario reads (its relief image, named run.json in
# the output directory); nothing is written, not even the tiles/ directory.
mkdir "$tmp/bk"
printf 'domain: {min: [0, 0, 0], max: [100, 100, 100]}\nterrain: {elevation: 90}\nkey_points:\n  - {type: sink, position: [10, 10, 80]}\n  - {type: spring, position: [90, 90, 20]}\nblocks:\n  tile_size: 10\n  strata: [{name: a, tile: tabular}]\n  warp: {relief: image, image: run.json, amplitude: 0.1}\n' > "$tmp/bk/s.yaml"
echo '{"not": "an image"}' > "$tmp/bk/run.json"
sum=$(cksum < "$tmp/bk/run.json")
run 2 "blocks -o the directory of its image" "$KARST" blocks "$tmp/bk/s.yaml" -o "$tmp/bk"
err_has "is the input $tmp/bk/run.json"
[ "$(cksum < "$tmp/bk/run.json")" = "$sum" ] || { echo "FAIL: blocks changed its image"; fail=1; }
[ -e "$tmp/bk/tiles" ] && { echo "FAIL: blocks made tiles/"; fail=1; }

# ensemble.json is reproducible: a resumed ensemble (a member deleted, the same command again)
# holds the same bytes as the uninterrupted one in every file but the run log ensemble_log.json,
# which says what was reused.
cp -r "$tmp/ens" "$tmp/ens2"
rm -rf "$tmp/ens2/realisations/0001" "$tmp/ens2/metrics.csv"
run 0 "resume the ensemble" "$KARST" ensemble "$MIN" -n 3 -o "$tmp/ens2" -j 1 --seed 4 -q
for f in $(cd "$tmp/ens" && find . -type f ! -name ensemble_log.json); do
  cmp -s "$tmp/ens/$f" "$tmp/ens2/$f" || { echo "FAIL: resumed $f differs"; fail=1; }
done
grep -q '"reused": 2,' "$tmp/ens2/ensemble_log.json" && grep -q '"computed": 1,' "$tmp/ens2/ensemble_log.json" ||
  { echo "FAIL: ensemble_log.json of the resumed run: $(cat "$tmp/ens2/ensemble_log.json")"; fail=1; }
grep -q wall_seconds "$tmp/ens/ensemble.json" && { echo "FAIL: ensemble.json holds the run log"; fail=1; }

# generate locks its directory: while this shell holds DIR/.generate.lock (flock(1) takes the
# same flock(2) lock as a running generate), a generate into DIR is refused and DIR's files stay as they were.
sum=$(cksum < "$tmp/net/network.vtp")
exec 9>"$tmp/net/.generate.lock"
flock -n 9 || { echo "FAIL: could not take the lock"; fail=1; }
run 1 "second generate into a locked DIR" "$KARST" generate "$MIN" -o "$tmp/net" --seed 9 --quiet
err_has "is in use by another karst generate"
exec 9>&-
[ "$(cksum < "$tmp/net/network.vtp")" = "$sum" ] || { echo "FAIL: the locked DIR changed"; fail=1; }
# once released, a run goes through and removes the lock file.
run 0 "generate after the lock is released" "$KARST" generate "$MIN" -o "$tmp/net" --quiet
[ -e "$tmp/net/.generate.lock" ] && { echo "FAIL: the lock file stayed"; fail=1; }

exit $fail
