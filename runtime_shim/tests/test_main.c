/* test_main.c - runs every C unit test of the runtime shim and prints "<n> passed, <m> failed". */
#include "hh_test.h"

int hh_test_failures;
static int passed, failed;

void hh_run_test(const char *name, hh_test_fn fn)
{
    hh_test_failures = 0;
    fn();
    if (hh_test_failures == 0) {
        passed++;
    } else {
        failed++;
        fprintf(stderr, "FAILED: %s\n", name);
    }
}

int main(void)
{
    run_nc_tests();
    run_module_tests();
    printf("%d passed, %d failed\n", passed, failed);
    return failed == 0 ? 0 : 1;
}
