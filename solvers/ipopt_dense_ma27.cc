#include <HSLLoader.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "quasiroll/solvers/ipopt_dense_ma27_internal.h"

namespace quasiroll::internal {
namespace {

// Ipopt 3.11 reaches the HSL solver MA27 through function pointers that its
// linear-solver loader exports (HSLLoader.h: LSL_setMA27). The four functions
// below take MA27's calling convention, exactly as Ipopt's
// Ma27TSolverInterface uses it, and solve the KKT system K x = r densely:
//   K = P L D L^T P^T  (Bunch-Kaufman, LAPACK dsytrf; D has 1x1 and 2x2
//   blocks), inertia from the blocks of D (Sylvester's law of inertia).
// quasiroll's NLPs have n + m <= ~60, where a dense factorization costs
// microseconds and MUMPS' per-call overhead dominated the solve
// (docs/performance.md). Storage, all inside the caller's arrays:
//   A[0, NZ)            the triplet values Ipopt wrote (never overwritten)
//   A[NZ, NZ + N^2)     the factor (column-major, lower triangle)
//   A[NZ + N^2, ...)    dsytrf workspace (kDenseWork * N doubles)
//   IW[0] = NZ, IW[1] = N, IW[2, 2 + N) = the pivot vector.
// A pivot block counts as zero only when it is exactly singular (d = 0, or
// det = 0 for a 2x2 block), as MA27 does with its default CNTL(3) = 0; then
// INFO(1) = 3 (rank deficient, INFO(2) = rank) and Ipopt perturbs the system.
// A relative threshold (N eps max|K_ij|) was tried and rejected: the barrier
// terms make legitimate pivots that small, and Ipopt then failed on the O3/O4
// oracles (docs/performance.md). MA27's pivot tolerance CNTL(1) has no
// counterpart: Bunch-Kaufman's growth bound alpha = (1 + sqrt 17) / 8
// chooses the pivots.
extern "C" {
void dsytrf_(const char* uplo, const int* n, double* a, const int* lda,
             int* ipiv, double* work, const int* lwork, int* info);
void dsytrs_(const char* uplo, const int* n, const int* nrhs, const double* a,
             const int* lda, const int* ipiv, double* b, const int* ldb,
             int* info);
}

constexpr int kDenseWork = 64;  // dsytrf block size bound (lwork = 64 N)

long DenseRealWorkspace(int n, int nz) {
  return static_cast<long>(nz) + static_cast<long>(n) * n +
         static_cast<long>(kDenseWork) * n;
}

void DenseMa27Id(ipfint* icntl, double* cntl) {
  std::fill(icntl, icntl + 30, 0);
  std::fill(cntl, cntl + 5, 0.0);
  cntl[0] = 0.1;  // MA27's default pivot tolerance (unused, see above)
}

void DenseMa27Ad(ipfint* n, ipfint* nz, const ipfint* irn, const ipfint* icn,
                 ipfint* /*iw*/, ipfint* /*liw*/, ipfint* /*ikeep*/,
                 ipfint* /*iw1*/, ipfint* nsteps, ipfint* iflag,
                 ipfint* /*icntl*/, double* /*cntl*/, ipfint* info,
                 double* ops) {
  std::fill(info, info + 20, 0);
  *iflag = 0;
  *nsteps = 1;
  *ops = std::pow(static_cast<double>(*n), 3) / 3.0;
  const long la = DenseRealWorkspace(*n, *nz);
  if (*n < 1 || la > std::numeric_limits<ipfint>::max()) {
    info[0] = -1;  // N out of range (MA27: INFO(1) = -1)
    return;
  }
  for (int k = 0; k < *nz; ++k) {
    if (irn[k] < 1 || irn[k] > *n || icn[k] < 1 || icn[k] > *n) {
      info[0] = 1;  // index out of range (Ipopt treats it as an error)
      info[1] = k + 1;
      return;
    }
  }
  info[4] = static_cast<ipfint>(la);  // NRLNEC: reals needed
  info[5] = *n + 2;                   // NIRNEC: integers needed
}

void DenseMa27Bd(ipfint* n, ipfint* nz, const ipfint* irn, const ipfint* icn,
                 double* a, ipfint* la, ipfint* iw, ipfint* liw,
                 ipfint* /*ikeep*/, ipfint* /*nsteps*/, ipfint* maxfrt,
                 ipfint* /*iw1*/, ipfint* /*icntl*/, double* /*cntl*/,
                 ipfint* info) {
  std::fill(info, info + 20, 0);
  const int dim = *n;
  const long need = DenseRealWorkspace(dim, *nz);
  if (*liw < dim + 2) {
    info[0] = -3;  // LIW too small; INFO(2) = the size needed
    info[1] = dim + 2;
    return;
  }
  if (*la < need) {
    info[0] = -4;  // LA too small; INFO(2) = the size needed
    info[1] = static_cast<ipfint>(need);
    return;
  }
  double* f = a + *nz;
  std::fill(f, f + static_cast<long>(dim) * dim, 0.0);
  for (int k = 0; k < *nz; ++k) {
    const int i = irn[k] - 1, j = icn[k] - 1;
    f[std::max(i, j) + static_cast<long>(std::min(i, j)) * dim] += a[k];
  }
  iw[0] = *nz;
  iw[1] = dim;
  int* ipiv = iw + 2;
  const int lwork = kDenseWork * dim;
  int lapack_info = 0;
  dsytrf_("L", &dim, f, &dim, ipiv, f + static_cast<long>(dim) * dim, &lwork,
          &lapack_info);
  *maxfrt = dim;
  info[8] = dim * dim;  // reals holding the factor
  info[9] = dim + 2;    // integers holding the factor
  if (lapack_info < 0) {
    info[0] = -5;  // cannot happen with valid arguments; Ipopt: singular
    return;
  }
  int negative = 0, zero = 0;
  for (int k = 0; k < dim;) {
    const double d11 = f[k + static_cast<long>(k) * dim];
    if (ipiv[k] > 0) {  // 1x1 block
      if (d11 == 0.0) {
        ++zero;
      } else if (d11 < 0) {
        ++negative;
      }
      k += 1;
    } else {  // 2x2 block rows k, k+1
      const double d21 = f[k + 1 + static_cast<long>(k) * dim];
      const double d22 = f[k + 1 + static_cast<long>(k + 1) * dim];
      const double det = d11 * d22 - d21 * d21;
      if (det == 0.0) {
        ++zero;  // at least one zero eigenvalue in the block
        if (d11 + d22 < 0) ++negative;
      } else if (det < 0) {
        ++negative;  // eigenvalues of opposite signs
      } else if (d11 + d22 < 0) {
        negative += 2;
      }
      k += 2;
    }
  }
  info[14] = negative;  // INFO(15): negative eigenvalues
  if (zero > 0 || lapack_info > 0) {
    info[0] = 3;  // rank deficient; INFO(2) = the rank
    info[1] = dim - std::max(zero, 1);
  }
}

void DenseMa27Cd(ipfint* n, double* a, ipfint* /*la*/, ipfint* iw,
                 ipfint* /*liw*/, double* /*w*/, ipfint* /*maxfrt*/,
                 double* rhs, ipfint* /*iw1*/, ipfint* /*nsteps*/,
                 ipfint* /*icntl*/, double* /*cntl*/) {
  const int dim = *n, one = 1;
  int lapack_info = 0;
  dsytrs_("L", &dim, &one, a + iw[0], &dim, iw + 2, rhs, &dim, &lapack_info);
}

}  // namespace

void InstallDenseMa27() {
  static std::once_flag once;
  std::call_once(once, [] {
    LSL_setMA27(&DenseMa27Ad, &DenseMa27Bd, &DenseMa27Cd, &DenseMa27Id);
  });
}

}  // namespace quasiroll::internal
