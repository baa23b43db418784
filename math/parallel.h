// math/parallel.h - OpenMP loops whose failures reach the caller. An exception thrown inside an
// OpenMP region must not leave it (the runtime would call std::terminate), so every body runs in
// a try block; after the loop the exception of the lowest failing index is rethrown, which makes
// the error reported independent of the thread count and the schedule.
#pragma once

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

/// body(i) for i = 0 .. n-1 in parallel, items handed out one at a time (dynamic schedule), on
/// `threads` threads (0: OpenMP's default); rethrows the exception of the lowest failing i once
/// every item has run or failed. Index is int or long.
template <class Index, class Body>
void parallel_for(Index n, Body&& body, int threads = 0) {
    std::vector<std::exception_ptr> errors;
    bool failed = false;
#ifdef _OPENMP
    const int n_threads = threads > 0 ? threads : omp_get_max_threads();
#else
    (void)threads;
#endif
#pragma omp parallel for schedule(dynamic, 1) num_threads(n_threads)
    for (Index i = 0; i < n; ++i) {
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
    }
    if (!failed) return;
    for (const std::exception_ptr& e : errors)
        if (e) std::rethrow_exception(e);
}

}  // namespace mbr
