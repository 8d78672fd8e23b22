#!/bin/sh
# compare_runs.sh - run example commands with two builds and compare their CSV files in every column
# but the wall-clock seconds (a refactor must not move a number).
#
#   tools/compare_runs.sh REF_BUILD NEW_BUILD WORKDIR CASEFILE
#
# CASEFILE: one case per line, "name | reference command | new command | csv files", the commands
# relative to the build directories ({B} stands for the build directory), the csv files relative to the
# output directory ({O} in the commands). A .csv file whose header names a column "seconds" (the
# drivers' wall-clock time) has that column left out; other files are compared whole. Lines starting
# with # are skipped.
# Prints one line per case and file (SAME / DIFFERS / MISSING) and ends with "N same, N differ";
# exit status 1 if any differs.
#
# Example line:
#   single25 | {B}/femdem_biaxial --test single --steps 25 --out {O} | {B}/femdem_biaxial --test single --steps 25 --out {O} | biaxial.csv single_element.csv
set -u
[ $# -eq 4 ] || { echo "usage: $0 REF_BUILD NEW_BUILD WORKDIR CASEFILE" >&2; exit 2; }
ref=$1 new=$2 work=$3 cases=$4
mkdir -p "$work" || exit 2
same=0 differ=0
strip() { # file -> stdout without the column named "seconds" of a driver CSV
    case "$1" in
    *.csv) awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == "seconds") s = i }
        { o = ""; for (i = 1; i <= NF; ++i) if (i != s) o = o (o == "" ? "" : ",") $i; print o }' "$1" ;;
    *) cat "$1" ;;
    esac
}
while IFS='|' read -r name rcmd ncmd files; do
    name=$(echo "$name" | tr -d ' ')
    case "$name" in '' | \#*) continue ;; esac
    for side in ref new; do
        if [ $side = ref ]; then b=$ref c=$rcmd; else b=$new c=$ncmd; fi
        o="$work/$name.$side"
        rm -rf "$o"
        cmd=$(echo "$c" | sed "s#{B}#$b#g; s#{O}#$o#g")
        start=$(date +%s)
        sh -c "$cmd" >"$o.out" 2>&1
        echo "  $name ($side): exit $?, $(($(date +%s) - start)) s: $cmd"
    done
    for f in $files; do
        a="$work/$name.ref/$f" n="$work/$name.new/$f"
        if [ ! -f "$a" ] || [ ! -f "$n" ]; then
            echo "MISSING $name $f"
            differ=$((differ + 1))
        elif [ "$(strip "$a" | cksum)" = "$(strip "$n" | cksum)" ]; then
            echo "SAME    $name $f ($(wc -l <"$a") lines)"
            same=$((same + 1))
        else
            echo "DIFFERS $name $f"
            strip "$a" >"$work/$name.ref.cmp"
            strip "$n" >"$work/$name.new.cmp"
            diff "$work/$name.ref.cmp" "$work/$name.new.cmp" | head -n 6
            differ=$((differ + 1))
        fi
    done
done <"$cases"
echo "$same same, $differ differ"
[ "$differ" -eq 0 ]
