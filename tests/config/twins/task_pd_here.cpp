// The twin of test_kinds.py's registered law "task-pd-here", compiled apart (nnrobust/twin.hpp):
// the example's TaskPD in C++ (examples/controllers/task_pd.cpp), registered under the law's twin.
#include "nnrobust/twin.hpp"
#include "../../../examples/controllers/task_pd.cpp"

NNROBUST_LAW("task-pd-here", TaskPD);
