#!/bin/sh
# curve_gap.sh - how far apart two stress-strain curves are, window by window.
#
#   tools/curve_gap.sh A.csv B.csv S [XCOL YCOL]
#
# Both curves (CSV files with a header line; columns XCOL and YCOL, default
# `strain` and `stress`) are interpolated linearly on 1000 strains spread over
# [0, S]; the mean of A - B over each of ten equal strain windows is printed as
# a percentage of B's peak, then the largest of the ten and the ratio of the
# peaks. This is the measure femdem_nonlocal's element tests print as
# rve_alone_dev_pct (one element against the RVE alone); here it compares any
# two runs, e.g. the RVE alone with two increment counts:
#
#   tools/curve_gap.sh RUN1/rve_alone.csv RUN2/rve_alone.csv 0.1
#
# Exit status 2 on a bad argument or a file without the columns.
set -eu
if [ $# -ne 3 ] && [ $# -ne 5 ]; then
    echo "usage: $0 A.csv B.csv S [XCOL YCOL]" >&2
    exit 2
fi
for f in "$1" "$2"; do
    [ -r "$f" ] || { echo "$0: cannot read $f" >&2; exit 2; }
done
awk -F, -v S="$3" -v XC="${4:-strain}" -v YC="${5:-stress}" '
function interp(c, x,    lo, hi, m, t) {
    if (n[c] < 2 || x < X[c, 0] || x > X[c, n[c] - 1]) return "nan"
    lo = 0; hi = n[c] - 1
    while (hi - lo > 1) { m = int((lo + hi) / 2); if (X[c, m] <= x) lo = m; else hi = m }
    if (X[c, hi] == X[c, lo]) return Y[c, lo]
    t = (x - X[c, lo]) / (X[c, hi] - X[c, lo])
    return Y[c, lo] + t * (Y[c, hi] - Y[c, lo])
}
BEGIN { if (!(S + 0 > 0)) { print "curve_gap: S must be > 0" > "/dev/stderr"; bad = 1; exit 2 } }
FNR == 1 {
    c = (NR == FNR) ? 0 : 1; xc = yc = 0
    for (k = 1; k <= NF; k++) { if ($k == XC) xc = k; if ($k == YC) yc = k }
    if (!xc || !yc) { printf "curve_gap: %s has no column %s or %s\n", FILENAME, XC, YC > "/dev/stderr"; bad = 1; exit 2 }
    next
}
{ i = n[c] + 0; X[c, i] = $xc + 0; Y[c, i] = $yc + 0; if (!(c in pk) || $yc + 0 > pk[c]) pk[c] = $yc + 0; n[c]++ }
END {
    if (bad) exit 2
    if (n[0] < 2 || n[1] < 2 || !(pk[1] > 0)) { print "curve_gap: a curve has fewer than 2 rows or no positive peak" > "/dev/stderr"; exit 2 }
    dmax = 0; line = ""
    for (w = 0; w < 10; w++) {
        s = 0; m = 0
        for (k = 0; k < 100; k++) {
            x = S * (w * 100 + k + 0.5) / 1000
            a = interp(0, x); b = interp(1, x)
            if (a != "nan" && b != "nan") { s += a - b; m++ }
        }
        g = m ? s / m : 0
        line = line sprintf(" %.2f", 100 * g / pk[1])
        if ((g < 0 ? -g : g) > dmax) dmax = (g < 0 ? -g : g)
    }
    printf "window means of A - B [%% of B peak]:%s\n", line
    printf "largest %.3f %%, peaks A/B %.4f\n", 100 * dmax / pk[1], pk[0] / pk[1]
}' "$1" "$2"
