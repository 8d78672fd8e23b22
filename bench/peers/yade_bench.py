# yade_bench.py - the grainkit peer benchmark in YADE (bench/peers/run_peers.sh).
#
#   yade -jT -n -x bench/peers/yade_bench.py PACKING WARM STEPS REPS
#
# PACKING is a grainkit packing file (first line "dim N Lx Ly [Lz]", '#'
# comments, an optional "# cell h00 h01 ..." line with the full cell matrix,
# then "x y [z] r" per particle). Workload (bench/data/README.md): linear law
# with CONSTANT kn = 2e5 N/m, ks = 0.5 kn, Coulomb mu = 0.5, no damping,
# density 2650 (sphere masses, also in 2D), dt = 2.7e-6 s, simple shear
# velGrad[0,1] = 1.5 /s on the periodic cell, Verlet distance 0.25 mm (YADE
# enlarges every bound by verletDist, so a pair is seen 2 x 0.25 = 0.5 mm
# before contact, as the 0.5 mm skin of LAMMPS/grainkit).
#
# Constant kn in FrictPhys: Ip2_FrictMat_FrictMat_FrictPhys gives
# kn = 2 Ea Ra Eb Rb / (Ea Ra + Eb Rb) and ks = 2 Ea Ra va Eb Rb vb /
# (Ea Ra va + Eb Rb vb). Each particle gets its own material with
# E = 2e5 / R (so E R = 2e5 for every particle) and poisson v = 0.5: then
# kn = 2e5 and ks = 1e5 exactly for every pair - no approximation.
# 2D packings: spheres at z = 0 in a cell of depth 8 r_max, z translation and
# x/y rotations blocked; the stress is reported per unit depth (N/m, x Lz)
# as LAMMPS and grainkit do in 2D.
#
# Prints: "YADE n=.. dim=.. threads=.. steps=.. seconds_median=.. seconds=a,b,c
#          contacts0=.. contacts=.. sxx=.. syy=.. szz=.. sxy=.. (tension +, end)"
import math
import sys
import time

from yade import utils
from yade.wrapper import *  # noqa: F401,F403 (engines, materials)
import os
sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0])))  # yade -x sets argv[0] to this script
from pack2lammps import read_packing  # noqa: E402
try:
    from yade.minieigenHP import Matrix3
except ImportError:  # older YADE
    from minieigen import Matrix3

path, warm, steps, reps = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
KN, KT_RATIO, MU, RHO, DT, RATE, SKIN = 2e5, 0.5, 0.5, 2650.0, 2.7e-6, 1.5, 5e-4

dim, h, pts = read_packing(path)  # one reader for every peer script (pack2lammps.py)
n = len(pts)
rmax = max(p[3] for p in pts)
if dim == 2:
    h[2][2] = 8.0 * rmax

O.periodic = True
O.cell.hSize = Matrix3(h[0][0], h[0][1], h[0][2], h[1][0], h[1][1], h[1][2], h[2][0], h[2][1], h[2][2])
for (x, y, z, r) in pts:
    m = O.materials.append(FrictMat(young=KN / r, poisson=KT_RATIO, frictionAngle=math.atan(MU), density=RHO))
    b = utils.sphere((x, y, z), r, material=m)
    if dim == 2:
        b.state.blockedDOFs = 'zXY'
    O.bodies.append(b)

O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb()], verletDist=0.5 * SKIN),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_FrictPhys()],
                    [Law2_ScGeom_FrictPhys_CundallStrack()]),
    NewtonIntegrator(damping=0.0, gravity=(0, 0, 0)),
]
O.dt = DT
O.cell.velGrad = Matrix3(0, RATE, 0, 0, 0, 0, 0, 0, 0)

# Timing: O.run(n, True) returns through a polling wait (40 ms granularity
# here), so the clock is read inside the loop instead, by a PyRunner at the
# end of the engine list (after all the work of a step), every S steps.
O.run(1, True)
contacts0 = O.interactions.countReal()
O.run(max(warm - 2, 0), True)
marks = []
O.engines = O.engines + [PyRunner(iterPeriod=steps, initRun=True, command='marks.append(time.time())')]
O.run(reps * steps + 1, True)
assert len(marks) == reps + 1, 'PyRunner fired %d times, wanted %d' % (len(marks), reps + 1)
secs = [marks[k + 1] - marks[k] for k in range(reps)]
srt = sorted(secs)
med = srt[len(srt) // 2] if len(srt) % 2 else 0.5 * (srt[len(srt) // 2 - 1] + srt[len(srt) // 2])
st = utils.getStress()
scale = O.cell.hSize[2, 2] if dim == 2 else 1.0  # 2D: force per unit depth
print('YADE iter=%d n=%d dim=%d threads=%d steps=%d seconds_median=%.6g seconds=%s contacts0=%d contacts=%d '
      'sxx=%.6g syy=%.6g szz=%.6g sxy=%.6g' % (O.iter, n, dim, O.numThreads, steps, med, ','.join('%.6g' % s for s in secs),
                                               contacts0, O.interactions.countReal(), st[0, 0] * scale,
                                               st[1, 1] * scale, st[2, 2] * scale, st[0, 1] * scale))
sys.stdout.flush()
