/* A C host that loads the plugin with dlopen (linking nothing of Lodestone).
   First it makes only calls that succeed and closes the library: it must be
   unloaded then (dlopen with RTLD_NOLOAD finds nothing; no unique symbol pins
   it). Then it loads it again and goes through error paths (a refused
   version, a refused parameter, a missing VDB file: each an exception inside
   the library turned into a status); a failure stores the thread's last error
   in thread_local state, which keeps the library loaded until the thread
   exits (docs/plugin.md), so only dlclose's status is checked after that.
   Prints "dlopen host: ok" and exits 0 on success.
   Usage: test_plugin_dlopen <path of liblodestone_plugin.so> */
#include <dlfcn.h>
#include <stdio.h>
#include <string.h>

#include "lodestone/plugin/lodestone.h"

#include "c_check.h"

/* dlopens the plugin at `path` into *lib and returns its lodestone_get_api
   (NULL, with a message, when either fails). */
static lodestone_get_api_fn openPlugin(const char* path, void** lib) {
  lodestone_get_api_fn get = NULL;
  *lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
  if (!*lib) {
    fprintf(stderr, "dlopen: %s\n", dlerror());
    return NULL;
  }
  *(void**)&get = dlsym(*lib, "lodestone_get_api");
  CHECK(get != NULL);
  return get;
}

int main(int argc, char** argv) {
  void* lib = NULL;
  lodestone_get_api_fn get = NULL;
  const lodestone_api* api = NULL;
  lodestone_context* ctx = NULL;
  lodestone_fields* fields = NULL;
  lodestone_stage* stage = NULL;
  lodestone_stage_params params;

  if (argc != 2) {
    fprintf(stderr, "usage: %s <plugin>\n", argv[0]);
    return 2;
  }
  /* Success only, then unloaded. */
  get = openPlugin(argv[1], &lib);
  if (!get) return 1;
  CHECK(get(LODESTONE_API_VERSION_MAJOR, LODESTONE_API_VERSION_MINOR, &api) == LODESTONE_OK);
  if (!api) return 1;
  CHECK(api->context_create(&ctx) == LODESTONE_OK);
  CHECK(api->fields_create(ctx, &fields) == LODESTONE_OK);
  {
    const double H[3] = {0.0, 0.0, 1e4}, x[3] = {0.0, 0.0, 0.0};
    double out[3] = {0.0, 0.0, 0.0};
    CHECK(api->fields_add_uniform(fields, H) == LODESTONE_OK);
    CHECK(api->fields_evaluate(fields, x, 0.0, out) == LODESTONE_OK && out[2] == 1e4);
  }
  CHECK(api->fields_destroy(fields) == LODESTONE_OK);
  CHECK(api->context_destroy(ctx) == LODESTONE_OK);
  fields = NULL;
  ctx = NULL;
  api = NULL;
  CHECK(dlclose(lib) == 0);
  lib = dlopen(argv[1], RTLD_NOW | RTLD_NOLOAD);
  if (lib) {
    fprintf(stderr, "the plugin is still loaded after dlclose\n");
    ++failures;
    dlclose(lib);
  }

  /* Error paths. */
  get = openPlugin(argv[1], &lib);
  if (!get) return 1;

  CHECK(get(LODESTONE_API_VERSION_MAJOR + 1, 0, &api) == LODESTONE_ERROR_VERSION && api == NULL);
  CHECK(get(LODESTONE_API_VERSION_MAJOR, LODESTONE_API_VERSION_MINOR, &api) == LODESTONE_OK);
  if (!api) return 1;
  CHECK(api->context_create(&ctx) == LODESTONE_OK);
  params.struct_size = sizeof params;
  CHECK(api->stage_params_default(&params) == LODESTONE_OK);
  params.grid.dx = -1.0;
  CHECK(api->stage_create(ctx, &params, &stage) == LODESTONE_ERROR_INVALID_ARGUMENT && stage == NULL);
  CHECK(strstr(api->context_last_error(ctx), "-1") != NULL);
  CHECK(api->fields_create(ctx, &fields) == LODESTONE_OK);
  {
    const lodestone_status s = api->fields_add_vdb(fields, "/nonexistent/field.vdb", "H");
    CHECK(s == LODESTONE_ERROR_IO || s == LODESTONE_ERROR_NOT_BUILT);
  }
  CHECK(api->fields_destroy(fields) == LODESTONE_OK);
  CHECK(api->context_destroy(ctx) == LODESTONE_OK);

  CHECK(dlclose(lib) == 0);
  if (failures) return 1;
  printf("dlopen host: ok\n");
  return 0;
}
