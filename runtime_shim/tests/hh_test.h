/* hh_test.h - a tiny assertion harness for the runtime shim's C unit tests. */
#ifndef HH_TEST_H
#define HH_TEST_H

#include <stdio.h>

extern int hh_test_failures; /* failed checks in the test that is running */

#define CHECK(cond)                                                                  \
    do {                                                                             \
        if (!(cond)) {                                                               \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
            hh_test_failures++;                                                      \
        }                                                                            \
    } while (0)

#define CHECK_EQ(actual, expected)                                                          \
    do {                                                                                    \
        long long a_ = (long long)(actual), e_ = (long long)(expected);                    \
        if (a_ != e_) {                                                                     \
            fprintf(stderr, "%s:%d: check failed: %s == %s (%lld != %lld)\n", __FILE__,    \
                    __LINE__, #actual, #expected, a_, e_);                                  \
            hh_test_failures++;                                                             \
        }                                                                                   \
    } while (0)

typedef void (*hh_test_fn)(void);
void hh_run_test(const char *name, hh_test_fn fn);
#define RUN(fn) hh_run_test(#fn, fn)

void run_nc_tests(void);
void run_module_tests(void);

#endif
