// The header a law in C++ is written against (docs/extending.md#a-law-in-c): the one the shipped
// laws use (csrc/controllers/laws/law.hpp): Law, LawParams, LawContext, TaskReference, Output,
// and NNROBUST_USER_LAW. Installed with the package as nnrobust/law.hpp.
#pragma once

#include "controllers/laws/law.hpp"
