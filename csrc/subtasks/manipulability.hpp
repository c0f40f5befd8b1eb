// nnrobust/subtasks/manipulability.py's det and adjugate of a small J J^T (m <= 3 in closed form),
// shared by the criteria, the nominal models' manipulability gradient and the recording.
#pragma once

#include "../types.hpp"

namespace nnrobust {

double det_small(const Matrix &A);       // manipulability.det: closed form for m <= 3, else LU
Matrix adjugate_small(const Matrix &A);  // manipulability.adjugate for m <= 3

}  // namespace nnrobust
