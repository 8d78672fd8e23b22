/* fuzz_gmsh.c - libFuzzer harness: gk_mesh_parse_gmsh on arbitrary bytes.
 *
 * Every input must give GK_OK or an error with a message; never a crash,
 * undefined behaviour or a leak. On GK_OK the mesh must be what the reader
 * promises (a supported element type, every connectivity entry a node of
 * the mesh, finite coordinates), and the FEM on top of it must either
 * refuse it with a message (gk_mesh_check: degenerate or inverted
 * elements) or build its matrix pattern and assemble an elastic stiffness.
 * Build and run: make fuzz (tests/fuzz/replay.c explains the layout). */
#define GK_IMPLEMENTATION
#include "gk_fem.h"  /* the FEM on top: gk_quad_rule, gk_fem_assemble */
#include "gk_mesh.h" /* the parser under test */
#include "fuzz_check.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    gk_mesh m;
    gk_err e;
    gk_quad q;
    gk_csr K;
    gk_result r;
    int k;
    e.msg[0] = '\0';
    r = gk_mesh_parse_gmsh((const char *)data, size, &m, NULL, &e);
    if (r != GK_OK) {
        FUZZ_CHECK(e.msg[0] != '\0' && e.code == r);
        return 0;
    }
    FUZZ_CHECK((m.type == GK_Q4 || m.type == GK_Q8 || m.type == GK_HEX8) && m.dim == gk_fem_dim(m.type) &&
               m.npe == gk_fem_npe(m.type) && m.nelem >= 1 && m.nnode >= 1);
    for (k = 0; k < m.nelem * m.npe; ++k) FUZZ_CHECK(m.conn[k] >= 0 && m.conn[k] < m.nnode);
    for (k = 0; k < m.nnode * m.dim; ++k) FUZZ_CHECK(isfinite(m.x[k]));
    FUZZ_CHECK(gk_quad_rule(&q, m.type, 2, &e) == GK_OK);
    r = gk_mesh_check(&m, &q, &e);
    if (r != GK_OK) {
        FUZZ_CHECK(e.msg[0] != '\0');
    } else if (m.nelem <= 256) {
        double *D = (double *)malloc((size_t)m.nelem * q.n * 81 * sizeof(double));
        int n4 = m.dim * m.dim * m.dim * m.dim, g;
        FUZZ_CHECK(gk_csr_from_mesh(&K, &m, NULL, &e) == GK_OK);
        FUZZ_CHECK(D != NULL);
        gk_fem_elastic_tangent(m.dim, 1e7, 0.3, D);
        for (g = 1; g < m.nelem * q.n; ++g) memcpy(D + (size_t)g * n4, D, (size_t)n4 * sizeof(double));
        FUZZ_CHECK(gk_fem_assemble(&m, &q, D, NULL, &K, NULL, &e) == GK_OK);
        for (k = 0; k < K.nnz; ++k) FUZZ_CHECK(isfinite(K.val[k]));
        free(D);
        gk_csr_free(&K);
    }
    gk_mesh_free(&m);
    return 0;
}
