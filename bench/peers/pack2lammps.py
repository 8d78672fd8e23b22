#!/usr/bin/env python3
"""pack2lammps.py - grainkit packing file -> LAMMPS / LIGGGHTS data file.

    python3 bench/peers/pack2lammps.py PACKING OUT.data [--density 2650]
            [--shear-rate 1.5] [--style sphere|granular] [--orthogonal]

Packing format (gk_packing_read in include/gk_dem.h): first line
"2 N Lx Ly" or "3 N Lx Ly Lz", then '#' comment lines (an optional
"# cell h00 h01 ... " line gives a skewed cell matrix h, x = h s, row-major),
then N lines "x y r" (2D) or "x y z r" (3D) in metres.

Output: atom_style sphere (LAMMPS) / granular (LIGGGHTS) data file, columns
"id type diameter density x y z", one atom type, a triclinic box
(xy xz yz line; --orthogonal leaves it out, for codes without triclinic
support) and a Velocities section with the affine field of simple shear
vx = rate * (y - ylo) and the spin of that field, wz = -rate/2, which is
where grainkit starts (its fluctuating velocities are zero, particles spin
with the cell). 2D: z = 0, box z in [-zh, zh] with zh = 2 r_max.
Standard library only.
"""
import sys


def read_packing(path):
    with open(path) as f:
        lines = f.read().splitlines()
    head = lines[0].split()
    dim, n = int(head[0]), int(head[1])
    L = [float(v) for v in head[2:2 + dim]]
    h = [[0.0] * 3 for _ in range(3)]
    for a in range(dim):
        h[a][a] = L[a]
    pts = []
    for ln in lines[1:]:
        s = ln.strip()
        if not s:
            continue
        if s.startswith('#'):
            w = s[1:].split()
            if w and w[0] == 'cell':
                vals = [float(v) for v in w[1:]]
                for a in range(dim):
                    for b in range(dim):
                        h[a][b] = vals[dim * a + b]
            continue
        v = [float(t) for t in s.split()]
        if dim == 2:
            pts.append((v[0], v[1], 0.0, v[2]))
        else:
            pts.append((v[0], v[1], v[2], v[3]))
    if len(pts) != n:
        sys.exit('pack2lammps: %s announces %d particles but lists %d' % (path, n, len(pts)))
    return dim, h, pts


def main(argv):
    args, opt = [], {'--density': '2650', '--shear-rate': '1.5', '--style': 'sphere'}
    orthogonal = False
    i = 1
    while i < len(argv):
        a = argv[i]
        if a in ('-h', '--help'):
            print(__doc__)
            return 0
        if a == '--orthogonal':
            orthogonal = True
        elif a in opt:
            i += 1
            opt[a] = argv[i]
        else:
            args.append(a)
        i += 1
    if len(args) != 2:
        sys.stderr.write('usage: pack2lammps.py PACKING OUT.data [options] (see --help)\n')
        return 2
    dim, h, pts = read_packing(args[0])
    rho, rate = float(opt['--density']), float(opt['--shear-rate'])
    # LAMMPS wants an upper-triangular cell: a = (lx,0,0), b = (xy,ly,0),
    # c = (xz,yz,lz). A general h (columns = cell vectors) is rotated into
    # that form (QR by Gram-Schmidt); positions go through reduced
    # coordinates, wrapped into [0,1). The rotation is reported: the shear
    # is then applied along the rotated axes (differs by that angle).
    if dim == 2:
        h[2][2] = 1.0
    col = [[h[0][b], h[1][b], h[2][b]] for b in range(3)]
    dot = lambda u, v: u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
    lx = dot(col[0], col[0]) ** 0.5
    e1 = [c / lx for c in col[0]]
    xy = dot(col[1], e1)
    t = [col[1][k] - xy * e1[k] for k in range(3)]
    ly = dot(t, t) ** 0.5
    e2 = [c / ly for c in t]
    e3 = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
    xz, yz, lz = dot(col[2], e1), dot(col[2], e2), dot(col[2], e3)
    R = [[lx, xy, xz], [0.0, ly, yz], [0.0, 0.0, lz]]
    angle = max(abs(e1[1]), abs(e1[2]), abs(e2[2]), abs(e2[0]))
    if angle > 1e-12:
        sys.stderr.write('pack2lammps: cell rotated into LAMMPS form by ~%.3g rad\n' % angle)
    # inverse of the general h (3x3, Cramer)
    a = h
    det = (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
           + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]))
    inv = [[(a[(i + 1) % 3][(j + 1) % 3] * a[(i + 2) % 3][(j + 2) % 3]
             - a[(i + 1) % 3][(j + 2) % 3] * a[(i + 2) % 3][(j + 1) % 3]) / det for i in range(3)] for j in range(3)]
    rmax = max(p[3] for p in pts)
    out = []
    for (x, y, z, r) in pts:
        s = [inv[i][0] * x + inv[i][1] * y + inv[i][2] * z for i in range(3)]
        s = [c - (c // 1.0) for c in s]
        if dim == 2:
            s[2] = 0.0
        out.append((R[0][0] * s[0] + R[0][1] * s[1] + R[0][2] * s[2], R[1][1] * s[1] + R[1][2] * s[2],
                    R[2][2] * s[2], r))
    pts = out
    zlo = 0.0
    if dim == 2:
        lz, xz, yz, zlo = 4.0 * rmax, 0.0, 0.0, -2.0 * rmax
    if orthogonal and (xy or xz or yz):
        sys.exit('pack2lammps: --orthogonal asked for a skewed cell (xy %g xz %g yz %g)' % (xy, xz, yz))
    with open(args[1], 'w') as f:
        f.write('grainkit packing %s (%dD, %d particles) for LAMMPS/LIGGGHTS\n\n' % (args[0], dim, len(pts)))
        f.write('%d atoms\n1 atom types\n\n' % len(pts))
        f.write('0 %.17g xlo xhi\n0 %.17g ylo yhi\n%.17g %.17g zlo zhi\n' % (lx, ly, zlo, zlo + lz))
        if not orthogonal:
            f.write('%.17g %.17g %.17g xy xz yz\n' % (xy, xz, yz))
        f.write('\nAtoms%s\n\n' % ('  # ' + opt['--style'] if opt['--style'] == 'sphere' else ''))
        for k, (x, y, z, r) in enumerate(pts):
            f.write('%d 1 %.17g %.17g %.17g %.17g %.17g\n' % (k + 1, 2.0 * r, rho, x, y, z))
        f.write('\nVelocities\n\n')
        for k, (x, y, z, r) in enumerate(pts):
            f.write('%d %.17g 0 0 0 0 %.17g\n' % (k + 1, rate * y, -0.5 * rate))
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
