// The "ipopt" backend's linear solver: a dense Bunch-Kaufman LDL^T (LAPACK
// dsytrf) behind Ipopt 3.11's MA27 hooks (ipopt_dense_ma27.cc). Internal to
// the ipopt backend (compiled only with QUASIROLL_WITH_IPOPT); no
// third-party header here.
#pragma once

namespace quasiroll::internal {

// Makes Ipopt's "ma27" linear_solver the dense LDL^T, process-wide (Ipopt's
// LSL_setMA27); idempotent and thread-safe. Call before an
// IpoptApplication with linear_solver = ma27 initialises its algorithm.
void InstallDenseMa27();

}  // namespace quasiroll::internal
