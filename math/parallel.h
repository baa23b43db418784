// math/parallel.h - OpenMP loops whose failures reach the caller. An exception thrown inside an
// OpenMP region must not leave it (the runtime would call std::terminate), so every body runs in
// a try block; after the loop the exception of the lowest failing index is rethrown, which makes
// the error reported independent of the thread count and the schedule.
#pragma once

#include <algorithm>
#include <exception>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace mbr {

/// The OpenMP thread number inside a parallel region (0 outside, or without OpenMP).
inline int thread_index() {
#ifdef _OPENMP
    return omp_get_thread_num();
#else
    return 0;
#endif
}

/// The number of threads a parallel region would use.
inline int thread_count() {
#ifdef _OPENMP
    return omp_get_max_threads();
#else
    return 1;
#endif
}

/// Tasks a nested parallel_for splits its items into, per thread of the team: enough that the
/// uneven items of a receiver's stages (a sample behind nine occluders costs five times one in
/// the open) even out between threads, few enough that a task's overhead (about a microsecond)
/// stays small beside its items.
constexpr int nested_tasks_per_thread = 8;

/// body(i) for i = 0 .. n-1 in parallel, on `threads` threads (0: OpenMP's default); rethrows the
/// exception of the lowest failing i once every item has run or failed. Index is int or long.
///
/// At the top level the items are handed out one at a time (dynamic schedule). Inside a parallel
/// region (a receiver's stages, run by the solver's loop over the receivers of a shot) the items
/// become tasks: the thread that meets the loop runs them, and a thread of the team that has no
/// work left (waiting at the end of the outer loop) takes some of them, so that one big transfer
/// at the end of a shot no longer runs on one thread while the others wait. Tasks never nest:
/// inside one (omp_in_final) the loop runs on the thread that meets it. Each item writes its own
/// results, so the values do not depend on which thread runs which item.
template <class Index, class Body>
void parallel_for(Index n, Body&& body, int threads = 0) {
    std::vector<std::exception_ptr> errors;
    bool failed = false;
    auto run = [&](Index i) {
        try {
            body(i);
        } catch (...) {
#pragma omp critical(mbr_parallel_for_errors)
            {
                if (errors.empty()) errors.assign(static_cast<size_t>(n), nullptr);
                errors[static_cast<size_t>(i)] = std::current_exception();
                failed = true;
            }
        }
    };
#ifdef _OPENMP
    if (omp_in_final()) {
        for (Index i = 0; i < n; ++i) run(i);
    } else if (omp_in_parallel()) {
        const Index tasks = std::min<Index>(n, Index(omp_get_num_threads()) * nested_tasks_per_thread);
#pragma omp taskloop num_tasks(tasks) final(true)
        for (Index i = 0; i < n; ++i) run(i);
    } else {
        const int n_threads = threads > 0 ? threads : omp_get_max_threads();
#pragma omp parallel for schedule(dynamic, 1) num_threads(n_threads)
        for (Index i = 0; i < n; ++i) run(i);
    }
#else
    (void)threads;
    for (Index i = 0; i < n; ++i) run(i);
#endif
    if (!failed) return;
    for (const std::exception_ptr& e : errors)
        if (e) std::rethrow_exception(e);
}

}  // namespace mbr
