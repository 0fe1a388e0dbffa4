// IDENT_SIMD_CLONES: marks a numerical kernel to be compiled twice, for the baseline x86-64 and for x86-64-v3
// (AVX2, FMA), with the version run chosen once per process by the CPU (GCC's target_clones, an ifunc). The
// library itself is built for the baseline, so that one binary runs on every x86-64 machine; the kernels whose
// loops gain from wider vectors and fused multiply-adds take the newer instructions where the CPU has them.
// Empty for other compilers and targets, and under AddressSanitizer (whose instrumentation does not support
// ifuncs). The clones' results may differ in the last bits, as contraction into FMAs rounds once instead of twice.
#pragma once

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(__SANITIZE_ADDRESS__)
#define IDENT_SIMD_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define IDENT_SIMD_CLONES
#endif
