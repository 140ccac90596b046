// Whether this build runs under AddressSanitizer (gcc says so one way, clang another): one
// answer for the code that must behave differently there (no address-space limit on a child
// while ASan reserves terabytes) and for the tests that sample sparser in such a build.
#pragma once

namespace yelan {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kUnderAsan = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kUnderAsan = true;
#else
inline constexpr bool kUnderAsan = false;
#endif
#else
inline constexpr bool kUnderAsan = false;
#endif

}  // namespace yelan
