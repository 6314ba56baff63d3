/* The public header compiles as C99 (-std=c99 -pedantic-errors) and a C host
   can negotiate a version and use the table. Exit status 0 on success. */
#include "lodestone/plugin/lodestone.h"

#include <stdio.h>
#include <string.h>

#include "c_check.h"

int main(void) {
  const lodestone_api* api = NULL;
  lodestone_context* ctx = NULL;
  lodestone_fields* fields = NULL;
  double H[3] = {1.0, 2.0, 3.0}, x[3] = {0.0, 0.0, 0.0}, out[3] = {0.0, 0.0, 0.0};
  uint32_t count = 0;

  CHECK(lodestone_get_api(LODESTONE_API_VERSION_MAJOR + 1, 0, &api) == LODESTONE_ERROR_VERSION);
  CHECK(api == NULL);
  CHECK(lodestone_get_api(LODESTONE_API_VERSION_MAJOR, LODESTONE_API_VERSION_MINOR, &api) == LODESTONE_OK);
  if (!api) return 1;
  CHECK(api->major == LODESTONE_API_VERSION_MAJOR);
  CHECK(strlen(api->version_string()) > 0);
  CHECK(api->context_create(&ctx) == LODESTONE_OK);
  CHECK(api->fields_create(ctx, &fields) == LODESTONE_OK);
  CHECK(api->fields_add_uniform(fields, H) == LODESTONE_OK);
  CHECK(api->fields_count(fields, &count) == LODESTONE_OK && count == 1);
  CHECK(api->fields_evaluate(fields, x, 0.0, out) == LODESTONE_OK);
  CHECK(out[0] == 1.0 && out[1] == 2.0 && out[2] == 3.0);
  CHECK(api->fields_add_uniform(NULL, H) == LODESTONE_ERROR_NULL_HANDLE);
  CHECK(strstr(api->thread_last_error(), "fields") != NULL);
  CHECK(api->fields_destroy(fields) == LODESTONE_OK);
  CHECK(api->fields_destroy(fields) == LODESTONE_ERROR_INVALID_HANDLE); /* destroyed twice: a status, no crash */
  CHECK(api->minor >= 1 && api->network_create_from_json != NULL);
  CHECK(api->context_destroy(ctx) == LODESTONE_OK);
  CHECK(api->context_destroy(ctx) == LODESTONE_ERROR_INVALID_HANDLE);
  if (failures == 0) printf("C99 host: ok\n");
  return failures == 0 ? 0 : 1;
}
