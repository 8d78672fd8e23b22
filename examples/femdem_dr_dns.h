/* femdem_dr_dns.h - the direct numerical simulation of build/femdem_dr --test dns
 * (examples/femdem_dr.c; examples, not library): the specimen as one DEM scene.
 *
 * --test dns: the specimen as one DEM scene (gk_scene.h): the periodic
 * packing tiled --dns-tiles NXxNY times (1x2: 2L x L, 2x4: 4L x 2L; the
 * paper's DNS A and B with 441 and 1681 disks; here 205 NX NY disks plus
 * the boundary copies closing the right and top edges: 444 for 1x2), the
 * same contact law; bottom and top rigid frictionless platens (walls), the
 * sides confined by follower-pressure membranes along the boundary
 * particles (anchored to the platens, tension-only links), the top platen
 * servo-controlled to sigma0 in stage 1, then displacement-driven. An
 * isotropic step ends at the RVEs' E_kin / E_pot (--tol-energy, eq 31)
 * with the lid within 1 % of its target; a biaxial step, whose platen force
 * is the measurement, at E_kin / E_pot <= --dns-tol (1e-5): at 1e-3 the
 * force is read from a specimen still moving, and sigma_bar at 1 % of the
 * 820-disk cell below comes out 0.203 / 0.190 / 0.228 / 0.247 with steps of
 * 1 / 0.5 / 0.2 / 0.1 %, at 1e-5 0.202 / 0.207 / 0.204 / 0.202. The
 * paper drives its DNS by the servo frame of Liu et al. (2017) (tractions
 * in stage 1, displacements in stage 2); walls and membranes are the
 * closest equivalent grainkit has. Stresses from the platen force and the
 * membrane pressure.
 *
 * Tiling the RVE's cell repeats one arrangement of 205 disks: the default
 * cell's 444- and 1707-disk specimens slip at 2 and 3 % strain, where
 * specimens of larger cells do not (the manual of femdem_dr.c).
 * `--packing examples/data/frame820_a002.txt --dns-tiles 1x2` builds the
 * size of the paper's DNS B (1704 disks) from two copies of an 820-disk
 * cell made alike (gk_pack, the same radii and protocol).
 */
#ifndef FEMDEM_DR_DNS_H
#define FEMDEM_DR_DNS_H

#include "gk_scene.h"
#include "femdem_dr_io.h"

/* ------------------------------------------------------------------ the DNS */
typedef struct dns {
    gk_scene sc;
    int32_t *left, *right;
    int nl, nr, bottom, top;
    double width0, h0;
} dns;

/* the specimen: the periodic packing tiled nt[0] x nt[1] times, closed on the right and on the top
 * by the copies of the boundary particles of x = 0 and y = 0 (as the framed RVE); the chains are
 * the particles on x = 0 (left, top to bottom) and on x = W (right, bottom to top) */
static int dns_build(model *m, dns *D) {
    const opts *o = &m->o;
    const gk_packing *pk = &m->pk;
    gk_packing t, sp;
    gk_err err;
    gk_scene_def sd = gk_scene_def_default();
    int nx = o->tiles[0], ny = o->tiles[1], n, p, i, j, k = 0, extra = 0;
    double L0 = pk->h[0], L1 = pk->h[4], W = nx * L0, H = ny * L1, tol = 1e-9 * L0, rmax = 0.0;
    if (gk_packing_tile(pk, nx, ny, 1, &t, NULL, &err)) {
        fprintf(stderr, PROG ": %s\n", err.msg);
        return 1;
    }
    for (p = 0; p < pk->n; ++p) {
        int onx = fabs(pk->x[p]) <= tol, ony = fabs(pk->y[p]) <= tol;
        extra += (onx ? ny : 0) + (ony ? nx : 0) + (onx && ony);
        if (pk->r[p] > rmax) rmax = pk->r[p];
    }
    n = t.n + extra;
    if (gk_packing_init(&sp, 2, n, NULL, &err)) {
        fprintf(stderr, PROG ": %s\n", err.msg);
        return 1;
    }
    for (p = 0; p < t.n; ++p) sp.x[k] = t.x[p], sp.y[k] = t.y[p], sp.r[k] = t.r[p], ++k;
    for (p = 0; p < pk->n; ++p) {
        int onx = fabs(pk->x[p]) <= tol, ony = fabs(pk->y[p]) <= tol;
        if (onx)
            for (j = 0; j < ny; ++j) sp.x[k] = W, sp.y[k] = pk->y[p] + j * L1, sp.r[k] = pk->r[p], ++k;
        if (ony)
            for (i = 0; i < nx; ++i) sp.x[k] = pk->x[p] + i * L0, sp.y[k] = H, sp.r[k] = pk->r[p], ++k;
        if (onx && ony) sp.x[k] = W, sp.y[k] = H, sp.r[k] = pk->r[p], ++k;
    }
    gk_packing_free(&t);
    sd.dim = 2;
    sd.lo[0] = -0.25 * W, sd.hi[0] = 1.25 * W, sd.lo[1] = -0.25 * H, sd.hi[1] = 1.25 * H;
    sd.lost = GK_LOST_DELETE;
    sd.rve = rve_def(o);
    if (gk_scene_create(&D->sc, &sd, &sp)) {
        fprintf(stderr, PROG ": %s\n", gk_scene_error(&D->sc));
        gk_packing_free(&sp);
        return 1;
    }
    /* the chains: x = 0 downwards, x = W upwards (ids = indices of sp) */
    D->left = (int32_t *)xcalloc((size_t)n, sizeof(int32_t));
    D->right = (int32_t *)xcalloc((size_t)n, sizeof(int32_t));
    for (D->nl = D->nr = 0, p = 0; p < n; ++p) {
        if (fabs(sp.x[p]) <= tol) D->left[D->nl++] = p;
        if (fabs(sp.x[p] - W) <= tol) D->right[D->nr++] = p;
    }
    for (i = 1; i < D->nl; ++i) /* insertion sorts: left by y descending, right by y ascending */
        for (j = i; j > 0 && sp.y[D->left[j]] > sp.y[D->left[j - 1]]; --j) {
            int32_t x = D->left[j];
            D->left[j] = D->left[j - 1], D->left[j - 1] = x;
        }
    for (i = 1; i < D->nr; ++i)
        for (j = i; j > 0 && sp.y[D->right[j]] < sp.y[D->right[j - 1]]; --j) {
            int32_t x = D->right[j];
            D->right[j] = D->right[j - 1], D->right[j - 1] = x;
        }
    {
        gk_wall_def fl = gk_wall_def_default(), lid = gk_wall_def_default();
        gk_material wm;
        double ylo = 1e300, yhi = -1e300;
        for (p = 0; p < n; ++p) {
            if (sp.y[p] - sp.r[p] < ylo) ylo = sp.y[p] - sp.r[p];
            if (sp.y[p] + sp.r[p] > yhi) yhi = sp.y[p] + sp.r[p];
        }
        gk_scene_pair_material(&sd.rve.mat, NULL, &wm, &err);
        wm.friction = 0.0; /* smooth platens */
        fl.point[1] = ylo, fl.normal[1] = 1.0, fl.mat = wm;
        lid.point[1] = yhi, lid.normal[1] = -1.0, lid.mat = wm;
        lid.drive = GK_DRIVE_STRESS, lid.area = W * D->sc.rve.volume_factor, lid.target = 0.0;
        lid.max_speed = 1e-3 * D->sc.rve.rmin / D->sc.rve.dt; /* the RVEs' ramp */
        if (gk_scene_add_wall(&D->sc, &fl, &D->bottom) || gk_scene_add_wall(&D->sc, &lid, &D->top) ||
            gk_scene_add_membrane(&D->sc, D->nl, D->left, 0.0, sd.rve.mat.kn, D->top, D->bottom, NULL) ||
            gk_scene_add_membrane(&D->sc, D->nr, D->right, 0.0, sd.rve.mat.kn, D->bottom, D->top, NULL) ||
            gk_scene_prescribe(&D->sc, gk_scene_index(&D->sc, D->left[D->nl - 1]), NULL, NULL)) {
            fprintf(stderr, PROG ": %s\n", gk_scene_error(&D->sc));
            gk_packing_free(&sp);
            return 1;
        }
        D->h0 = yhi - ylo;
    }
    D->width0 = W;
    gk_packing_free(&sp);
    printf("femdem_dr: DNS of %d x %d cells: %d disks, %.4g x %.4g mm, chains of %d and %d\n", nx, ny, n,
           1e3 * W, 1e3 * H, D->nl, D->nr);
    return 0;
}

/* the chains' mean x (the width the pressures act across) */
static double dns_width(const dns *D) {
    double xl = 0.0, xr = 0.0, x[3];
    int k;
    for (k = 0; k < D->nl; ++k) gk_scene_position(&D->sc, gk_scene_index(&D->sc, D->left[k]), x), xl += x[0];
    for (k = 0; k < D->nr; ++k) gk_scene_position(&D->sc, gk_scene_index(&D->sc, D->right[k]), x), xr += x[0];
    return xr / D->nr - xl / D->nl;
}

/* relax to E_kin / E_pot <= tol (and, with the lid servo on, the lid within 1 % of its target); the
 * relaxation checks, or -1 after the message */
static long dns_relax(model *m, dns *D, double tol, long *steps) {
    gk_wall *lid = &D->sc.walls[D->top];
    long checks = 0;
    double ek, ep;
    for (;;) {
        int servo = lid->def.drive == GK_DRIVE_STRESS;
        if (gk_scene_step(&D->sc, 50)) {
            fprintf(stderr, PROG ": %s\n", gk_scene_error(&D->sc));
            return -1;
        }
        *steps += 50, ++checks;
        gk_frame_energy(&D->sc.rve, NULL, &ek, &ep);
        if ((ep > 0.0 ? ek <= tol * ep : ek == 0.0) &&
            (!servo || fabs(lid->resistance - lid->def.target * lid->def.area) <=
                           0.01 * lid->def.target * lid->def.area))
            return checks;
        if (*steps > 50L * m->o.max_dr) {
            ++m->unconverged;
            fprintf(stderr, PROG ": warning: the DNS did not relax (E_kin / E_pot %.2g)\n",
                    ep > 0 ? ek / ep : 0.0);
            return checks;
        }
    }
}

static void dns_row(model *m, dns *D, int step, int stage, long checks, long steps, row *r) {
    double w = dns_width(D), h = D->sc.walls[D->top].pos[1] - D->sc.walls[D->bottom].pos[1], phi[9], Fa[9];
    double s22 = D->sc.walls[D->top].resistance / (w * D->sc.rve.volume_factor), s11 = D->sc.mem[0].pressure;
    double J = w * h / (D->width0 * D->h0);
    gk_homog_fabric(&D->sc.rve, phi, Fa);
    r->v[0] = step, r->v[1] = stage;
    r->v[2] = stage == 2 ? (m->h_ic - h) / m->h_ic : (D->h0 - h) / D->h0;
    r->v[3] = s11 + s22 > 0.0 ? fabs((s11 - s22) / (s11 + s22)) : 0.0;
    r->v[4] = s11, r->v[5] = s22;
    r->v[6] = stage == 2 ? (J - m->J_ic) / m->J_ic : J - 1.0;
    r->v[7] = 2.0 * D->sc.rve.ncontacts / D->sc.rve.n, r->v[8] = gk_fabric_ratio(phi, 2);
    r->v[9] = (double)checks, r->v[10] = (double)steps, r->v[11] = gk_wtime() - m->t0;
}

static int run_dns(model *m) {
    const opts *o = &m->o;
    dns D;
    row r;
    int step, nsteps = o->iso_steps + o->steps;
    gk_wall *lid;
    memset(&D, 0, sizeof D);
    if (gk_packing_read(o->packing, &m->pk, NULL, NULL) && !m->pk.n) {
        fprintf(stderr, PROG ": cannot read %s\n", o->packing);
        return 1;
    }
    if (dns_build(m, &D)) return 1;
    lid = &D.sc.walls[D.top];
    m->h0 = D.h0, m->h_ic = D.h0, m->J_ic = 1.0;
    dns_row(m, &D, 0, 1, 0, 0, &r);
    add_row(m, &r);
    for (step = 1; step <= nsteps; ++step) {
        int stage = step <= o->iso_steps ? 1 : 2;
        long steps = 0, checks;
        if (stage == 1) {
            double p = o->pressure * step / o->iso_steps;
            D.sc.mem[0].pressure = D.sc.mem[1].pressure = p;
            lid->def.target = p, lid->def.area = dns_width(&D) * D.sc.rve.volume_factor;
        } else {
            double d = o->strain * m->h_ic / o->steps,
                   v = 1e-3 * D.sc.rve.rmin / D.sc.rve.dt; /* the RVEs' ramp */
            long n = (long)ceil(d / (v * D.sc.rve.dt));
            lid->def.drive = GK_DRIVE_VELOCITY;
            lid->def.velocity[1] = -d / (n * D.sc.rve.dt);
            if (gk_scene_step(&D.sc, n)) {
                fprintf(stderr, PROG ": %s\n", gk_scene_error(&D.sc));
                return 1;
            }
            steps += n;
            lid->def.velocity[1] = 0.0;
        }
        if ((checks = dns_relax(m, &D, stage == 1 ? o->tol_energy : o->dns_tol, &steps)) < 0) return 1;
        if (step == o->iso_steps) {
            m->h_ic = lid->pos[1] - D.sc.walls[D.bottom].pos[1];
            m->J_ic = dns_width(&D) * m->h_ic / (D.width0 * D.h0);
        }
        m->dem_total += steps;
        dns_row(m, &D, step, stage, checks, steps, &r);
        if (!isfinite(r.v[8])) return came_apart(step, "the specimen");
        add_row(m, &r);
        {
            char what[256];
            snprintf(what, sizeof what,
                     "stage %d  eps %.3f %%  sigma_bar %.4f  s11 %.4g s22 %.4g  DEM %ld  lost %ld", stage,
                     100.0 * r.v[2], r.v[3], r.v[4], r.v[5], steps, D.sc.lost);
            gk_progress(stderr, step, nsteps, m->t0, what);
        }
        if (write_csv(m, "dr.csv")) return 1;
        if ((o->vtk_every > 0 && step % o->vtk_every == 0) || step == nsteps) {
            char path[1024];
            gk_err err;
            snprintf(path, sizeof path, "%s/dns_%04d.vtk", o->out, step);
            if (gk_scene_write_vtk(&D.sc, path, &err)) {
                fprintf(stderr, PROG ": %s\n", err.msg);
                return 1;
            }
        }
    }
    if (write_svgs(m)) return 1;
    m->runs_total = nsteps;
    result_line(m);
    printf("DNS lost_particles=%ld\n", D.sc.lost);
    gk_scene_destroy(&D.sc);
    free(D.left), free(D.right);
    return 0;
}

#endif /* FEMDEM_DR_DNS_H */
