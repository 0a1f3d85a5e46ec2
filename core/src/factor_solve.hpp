#pragma once
// The constraint projection's solves with a sparse LDL^T factor (factor_solve.cpp), written once with Google Highway
// and dispatched at run time to the best instruction set the CPU has. ConstraintSystem (constraints.cpp) solves
// (Phi M^-1 Phi^T) y = r with it each time step, for every displacement component of a constraint block at once.
#include <cstddef>

namespace mtled::factor_solve {

// A = P^T L D L^T P with L unit lower triangular, stored by column without its diagonal (Eigen's SimplicialLDLT).
struct LdltFactor {
  std::size_t size = 0;
  const int* column_offsets = nullptr;  // L's column c: entries column_offsets[c] .. column_offsets[c + 1] - 1
  const int* row_index = nullptr;       // each entry's row, > its column
  const double* value = nullptr;
  const int* permutation = nullptr;          // P: row i of b goes to row permutation[i] of P b
  const double* inverse_diagonal = nullptr;  // 1 / D
};

// Values per row in solve()'s scratch: the components side by side, three padded to four so that a row's values are
// whole vectors.
constexpr std::size_t record_width(std::size_t components) { return components == 3 ? 4 : components; }

// y = A^-1 y for `components` (1 to 3) right-hand sides at once, in place. Row i of the factor is row rows[i] of y,
// whose values for the components lie at y[components * rows[i] + j]. scratch: record_width(components) * size
// doubles. The sums run in a fixed order: the result does not depend on the thread that calls.
void solve(const LdltFactor& factor, const std::size_t* rows, std::size_t components, double* y, double* scratch);

}  // namespace mtled::factor_solve
