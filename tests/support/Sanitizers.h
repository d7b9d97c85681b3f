#pragma once
// RHOT_ASAN: 1 where this translation unit is built with AddressSanitizer. GCC says so with
// __SANITIZE_ADDRESS__, Clang (the asan preset's compiler) with __has_feature(address_sanitizer).

#if defined(__SANITIZE_ADDRESS__)
#define RHOT_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RHOT_ASAN 1
#endif
#endif
#ifndef RHOT_ASAN
#define RHOT_ASAN 0
#endif
