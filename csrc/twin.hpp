// The header a twin compiled apart is written against (docs/extending.md#a-twin-in-c): a kind
// declared outside nnrobust (a path, criterion, disturbance, robust term or registered law) names
// one .cpp file as its `twin_source`; the file includes this header, defines its class against the
// shipped interface (Path, Criterion, Disturbance, RobustTerm, Law) and registers it under its
// Python twin's `twin` name with the shipped macro (NNROBUST_PATH, NNROBUST_CRITERION,
// NNROBUST_DISTURBANCE, NNROBUST_ROBUST_TERM, NNROBUST_LAW) at namespace scope. nnrobust compiles
// it with NNROBUST_TWIN_LIBRARY on first use and copies its registrations into the compiled loop.
// Installed with the package as nnrobust/twin.hpp.
#pragma once

#include "controllers/laws/law.hpp"
#include "controllers/robust_term.hpp"
#include "plant/disturbance.hpp"
#include "subtasks/criterion.hpp"
#include "trajectories/trajectory.hpp"
