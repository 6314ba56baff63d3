/* CHECK(cond) for the C hosts of the plugin tests: prints the failed
   condition with its file and line and counts it in `failures`. */
#ifndef LODESTONE_TEST_C_CHECK_H
#define LODESTONE_TEST_C_CHECK_H
#include <stdio.h>

static int failures = 0;

#define CHECK(cond)                                                      \
  do {                                                                   \
    if (!(cond)) {                                                       \
      fprintf(stderr, "%s:%d: failed: %s\n", __FILE__, __LINE__, #cond); \
      ++failures;                                                        \
    }                                                                    \
  } while (0)

#endif
