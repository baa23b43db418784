// math/simd.h - function multi-versioning for the hot loops that the compiler vectorises (the
// kernel of eq. (3) over a cell's points, Horner's rule over a shooter patch): the default
// build runs on any x86-64 processor and uses AVX2 where the processor has it.
#pragma once

#include <cstddef>  // for __GLIBC__

// MBR_VECTOR_CLONES before a function's definition compiles it twice, for AVX2 and for the
// baseline instruction set, and lets glibc's indirect-function resolver pick one at load time
// (GCC and Clang on x86-64 ELF with glibc). AVX2 alone does not enable fused multiply-add, so
// both clones round alike and give the same bits. Elsewhere it is empty (one baseline copy).
#if defined(__x86_64__) && defined(__ELF__) && defined(__GLIBC__) && defined(__has_attribute)
#if __has_attribute(target_clones)
#define MBR_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#endif
#endif
#ifndef MBR_VECTOR_CLONES
#define MBR_VECTOR_CLONES
#endif
