// Whether this CPU and its OS run x86-64-v3 code (AVX2, FMA, BMI1/2, F16C, LZCNT, MOVBE and the v2
// features under them; AVX state enabled by the OS), read with cpuid and xgetbv. The add-on's
// loader (addon/sd_lighting/native.py) calls it through ctypes in the portable build before it
// imports either: /proc/cpuinfo is Linux's alone, and a virtual machine may hide any feature.
#if defined(_MSC_VER)
#  include <intrin.h>
#  define SD_EXPORT extern "C" __declspec(dllexport)
#else
#  define SD_EXPORT extern "C" __attribute__((visibility("default")))
#  if defined(__x86_64__)
#    include <cpuid.h>
#  endif
#endif

namespace {

struct Registers {
  unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
};

// cpuid(leaf, subleaf); false where the CPU has no such leaf (or is not x86-64).
bool cpuid(unsigned leaf, unsigned subleaf, Registers& r) {
#if defined(_MSC_VER) && defined(_M_X64)
  int out[4];
  __cpuid(out, static_cast<int>(leaf & 0x80000000u));   // the highest leaf of the range
  if (static_cast<unsigned>(out[0]) < leaf) return false;
  __cpuidex(out, static_cast<int>(leaf), static_cast<int>(subleaf));
  r = {static_cast<unsigned>(out[0]), static_cast<unsigned>(out[1]), static_cast<unsigned>(out[2]),
       static_cast<unsigned>(out[3])};
  return true;
#elif defined(__x86_64__)
  return __get_cpuid_count(leaf, subleaf, &r.eax, &r.ebx, &r.ecx, &r.edx) != 0;
#else
  (void)leaf, (void)subleaf, (void)r;
  return false;
#endif
}

// XCR0: which register states the OS saves (bit 1 SSE, bit 2 AVX). Only with OSXSAVE set.
unsigned long long enabled_states() {
#if defined(_MSC_VER) && defined(_M_X64)
  return _xgetbv(0);
#elif defined(__x86_64__)
  unsigned eax = 0, edx = 0;
  __asm__ volatile("xgetbv" : "=a"(eax), "=d"(edx) : "c"(0));
  return (static_cast<unsigned long long>(edx) << 32) | eax;
#else
  return 0;
#endif
}

bool has(unsigned value, unsigned bits) { return (value & bits) == bits; }

}  // namespace

/// 1 where this CPU and OS run x86-64-v3 code, else 0 (also off x86-64).
SD_EXPORT int sd_cpu_supports_x86_64_v3() {
  Registers basic, extended, ext;
  if (!cpuid(1, 0, basic) || !cpuid(7, 0, extended) || !cpuid(0x80000001u, 0, ext)) return 0;
  // leaf 1 ECX: SSE3 0, SSSE3 9, FMA 12, CMPXCHG16B 13, SSE4.1 19, SSE4.2 20, MOVBE 22, POPCNT 23,
  // OSXSAVE 27, AVX 28, F16C 29
  const unsigned leaf1 = 1u << 0 | 1u << 9 | 1u << 12 | 1u << 13 | 1u << 19 | 1u << 20 | 1u << 22 |
                         1u << 23 | 1u << 27 | 1u << 28 | 1u << 29;
  const unsigned leaf7 = 1u << 3 | 1u << 5 | 1u << 8;    // EBX: BMI1 3, AVX2 5, BMI2 8
  const unsigned leaf81 = 1u << 0 | 1u << 5;             // ECX: LAHF/SAHF 0, LZCNT 5
  if (!has(basic.ecx, leaf1) || !has(extended.ebx, leaf7) || !has(ext.ecx, leaf81)) return 0;
  return has(static_cast<unsigned>(enabled_states()), 0x6u) ? 1 : 0;
}
