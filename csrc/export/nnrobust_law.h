/* nnrobust_law.h: a control law exported by `nnrobust export` (docs/export.md), callable from C,
 * C++ or anything with a C foreign-function interface; no Python at run time.
 *
 * The law is the compiled twin of the experiment's controller (the same C++ code the compiled loop
 * runs): at each control instant it takes the time and the measured joint positions and
 * velocities and returns the commanded joint torques; it keeps its own state (the adaptive weights
 * of the NN compensator, a registered law's state) from one step to the next.
 *
 * Threads: one law object is used by one thread at a time; distinct objects are independent
 * (each owns its model and workspace), so several may run on several threads at once.
 */
#ifndef NNROBUST_LAW_H
#define NNROBUST_LAW_H

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_WIN32)
#define NNROBUST_LAW_API __declspec(dllexport)
#else
#define NNROBUST_LAW_API __attribute__((visibility("default")))
#endif

typedef struct nnrobust_law nnrobust_law;

/* The law written into this library by `nnrobust export`: its settings and its nominal model as
 * numbers (libnnrobust_law). NULL on failure: nnrobust_law_last_error() says why. Allocates. */
NNROBUST_LAW_API nnrobust_law *nnrobust_law_create(void);

/* A law from a description written by `nnrobust export` (the text of its law.description file;
 * libnnrobust_core). NULL on failure: nnrobust_law_last_error() says why. Allocates. */
NNROBUST_LAW_API nnrobust_law *nnrobust_law_create_from(const char *description);

/* A law in C++ of a user's (NNROBUST_USER_LAW, docs/extending.md#a-law-in-c) is compiled into
 * its export's libnnrobust_law, whose nnrobust_law_create registers it with this call first: its
 * factory (the function NNROBUST_USER_LAW defines, by its address) under the name the description
 * gives. 0 on success, -1 on an error (nnrobust_law_last_error()). */
typedef void (*nnrobust_law_function)(void);
NNROBUST_LAW_API int nnrobust_law_add_native(const char *name, nnrobust_law_function factory);

/* The number of joints n: the entries of q, v and tau. */
NNROBUST_LAW_API int nnrobust_law_dof(const nnrobust_law *law);

/* The control period the law was tuned and simulated at [s]. */
NNROBUST_LAW_API double nnrobust_law_period(const nnrobust_law *law);

/* One control step at time t [s] (from the start of the trajectory) with the measured joint
 * positions q [rad or m] and velocities v (n entries each): writes the commanded torques into
 * tau_out (n entries, N m or N) and advances the law's state. Returns 0 on success, 1 when the
 * torque is not finite (the caller should apply its safe reaction; the state is not advanced),
 * 2 when the values are absurd: a measured position beyond its joint's range by more than the
 * range's width, or a command above 10 times its joint's effort limit (tau_out holds it: do not
 * apply it; apply the safe reaction; the state is not advanced), -1 on an error
 * (nnrobust_law_last_error()), among them a step that kept memory it allocated (which the next
 * step would hand out again). */
NNROBUST_LAW_API int nnrobust_law_step(nnrobust_law *law, double t, const double *q, const double *v,
                                       double *tau_out);

/* The allocations of this law's steps so far that did not fit its arena and went to the system
 * allocator (0 in the cases tests/test_export.py steps); -1 where the library was built without
 * the arena (a linker without --wrap): its steps then allocate from the heap. A step takes its
 * temporaries from a block the law reserves at create, so it never calls malloc or operator new. */
NNROBUST_LAW_API long nnrobust_law_heap_requests(const nnrobust_law *law);

/* The law's state back to its initial value (the adaptive weights to their start). */
NNROBUST_LAW_API void nnrobust_law_reset(nnrobust_law *law);

NNROBUST_LAW_API void nnrobust_law_destroy(nnrobust_law *law);

/* Why the last create or step of this thread failed ("" when none did). */
NNROBUST_LAW_API const char *nnrobust_law_last_error(void);

#ifdef __cplusplus
}
#endif

#endif /* NNROBUST_LAW_H */
