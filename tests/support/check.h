/* A few assertion macros for the C test programs. Each program ends with check_report(), which
 * prints "N passed, M failed" and returns the exit status ctest judges. A failed check prints
 * file, line and both values, and the test goes on so one run shows every difference. */
#ifndef TESTS_CHECK_H
#define TESTS_CHECK_H

#include <stdint.h>
#include <stdio.h>
#include <string.h>

static int check_passed_;
static int check_failed_;
static const char *check_test_name_ = "";

static inline void check_hex_(const char *label, const uint8_t *p, size_t n)
{
    fprintf(stderr, "    %s (%zu):", label, n);
    for (size_t i = 0; i < n; i++) {
        fprintf(stderr, " %02X", p[i]);
    }
    fprintf(stderr, "\n");
}

#define CHECK(cond)                                                                            \
    do {                                                                                       \
        if (cond) {                                                                            \
            check_passed_++;                                                                   \
        } else {                                                                               \
            check_failed_++;                                                                   \
            fprintf(stderr, "%s:%d: [%s] CHECK(%s) failed\n", __FILE__, __LINE__,              \
                    check_test_name_, #cond);                                                  \
        }                                                                                      \
    } while (0)

#define CHECK_EQ(actual, expected)                                                             \
    do {                                                                                       \
        long long a_ = (long long)(actual);                                                    \
        long long e_ = (long long)(expected);                                                  \
        if (a_ == e_) {                                                                        \
            check_passed_++;                                                                   \
        } else {                                                                               \
            check_failed_++;                                                                   \
            fprintf(stderr, "%s:%d: [%s] %s == %lld (0x%llX), expected %s == %lld (0x%llX)\n", \
                    __FILE__, __LINE__, check_test_name_, #actual, a_, a_, #expected, e_, e_); \
        }                                                                                      \
    } while (0)

#define CHECK_STR(actual, expected)                                                            \
    do {                                                                                       \
        const char *a_ = (actual);                                                             \
        const char *e_ = (expected);                                                           \
        if (a_ != NULL && strcmp(a_, e_) == 0) {                                               \
            check_passed_++;                                                                   \
        } else {                                                                               \
            check_failed_++;                                                                   \
            fprintf(stderr, "%s:%d: [%s] \"%s\", expected \"%s\"\n", __FILE__, __LINE__,      \
                    check_test_name_, a_ ? a_ : "(null)", e_);                                 \
        }                                                                                      \
    } while (0)

/* CHECK_BYTES(buf, len, 0x10, 0x02, ...): exact bytes on the wire. */
#define CHECK_BYTES(actual, actual_len, ...)                                                   \
    do {                                                                                       \
        const uint8_t e_[] = {__VA_ARGS__};                                                    \
        size_t al_ = (size_t)(actual_len);                                                     \
        if (al_ == sizeof e_ && memcmp((actual), e_, sizeof e_) == 0) {                        \
            check_passed_++;                                                                   \
        } else {                                                                               \
            check_failed_++;                                                                   \
            fprintf(stderr, "%s:%d: [%s] bytes differ\n", __FILE__, __LINE__,                  \
                    check_test_name_);                                                         \
            check_hex_("actual  ", (const uint8_t *)(actual), al_);                            \
            check_hex_("expected", e_, sizeof e_);                                             \
        }                                                                                      \
    } while (0)

#define RUN_TEST(fn)                                                                           \
    do {                                                                                       \
        check_test_name_ = #fn;                                                                \
        fn();                                                                                  \
    } while (0)

static inline int check_report(void)
{
    printf("%d passed, %d failed\n", check_passed_, check_failed_);
    return check_failed_ == 0 && check_passed_ > 0 ? 0 : 1;
}

#endif
