// The test runner's main(), natively and on the M4 (where argv comes through semihosting).
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest.h>
