// test/test_parallel.cpp - parallel_for (math/parallel.h): nested loops become tasks inside a
// parallel region, run every item once, and report the lowest failing item's exception.
#include <atomic>
#include <catch2/catch.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "math/check.h"
#include "math/parallel.h"

using namespace mbr;

namespace {

/// An outer loop of `outer` items, each running an inner loop of `inner` items that writes
/// i * inner + j into its own slot (the solver's receivers and their stages).
std::vector<long> nested_values(int outer, int inner, int threads) {
    std::vector<long> out(size_t(outer) * inner, -1);
    parallel_for(
        outer,
        [&](int i) {
            parallel_for(inner, [&](int j) { out[size_t(i) * inner + j] = long(i) * inner + j; });
        },
        threads);
    return out;
}

}  // namespace

TEST_CASE("parallel: nested loops run every item once, with any thread count", "[parallel]") {
    std::vector<long> expected(size_t(7) * 300);
    for (size_t k = 0; k < expected.size(); ++k) expected[k] = long(k);
    for (int threads : {1, 2, 3}) {
        CAPTURE(threads);
        CHECK(nested_values(7, 300, threads) == expected);
    }
    // Three levels: the innermost runs inside a task (final), on the thread that meets it.
    std::atomic<long> count{0};
    parallel_for(
        3,
        [&](int) {
            parallel_for(5, [&](int) { parallel_for(11, [&](int) { ++count; }); });
        },
        2);
    CHECK(count == 3 * 5 * 11);
}

TEST_CASE("parallel: a nested loop's failure reaches the outer caller, the lowest item's",
          "[parallel]") {
    try {
        parallel_for(
            4,
            [](int i) {
                parallel_for(50, [i](int j) {
                    MBR_CHECK_MSG(!(i == 2 && j % 10 == 7), "item " << i << "." << j);
                });
            },
            2);
        FAIL("no exception");
    } catch (const CheckFailure& e) {
        CHECK_THAT(e.what(), Catch::Contains("item 2.7)"));
    }
}
