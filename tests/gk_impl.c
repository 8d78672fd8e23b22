/* gk_impl.c - the grainkit implementation in one object, the way a project of
 * several files builds it: this file defines GK_IMPLEMENTATION, every other
 * file includes the headers for their declarations only. The Makefile compiles
 * it once per build (normal, ASan+UBSan, no-SIMD) and links it into every test
 * that does not define GK_IMPLEMENTATION itself; the tests that change the
 * implementation's configuration (GK_REAL_FLOAT, GK_DEM_PAR_MIN) still
 * compile their own. */
#define GK_IMPLEMENTATION
#include "gk_base.h"
#include "gk_cells.h"
#include "gk_contact.h"
#include "gk_dem.h"
#include "gk_dofmap.h"
#include "gk_explicit.h"
#include "gk_fem.h"
#include "gk_frame.h"
#include "gk_homog.h"
#include "gk_hybrid.h"
#include "gk_io.h"
#include "gk_mesh.h"
#include "gk_mpm.h"
#include "gk_nonlocal.h"
#include "gk_packing.h"
#include "gk_pcell.h"
#include "gk_scene.h"
#include "gk_sparse.h"
#include "gk_twoscale.h"
