#include <lodestone/plugin/lodestone.h>
#include <stdio.h>

int main(void) {
  const lodestone_api* api = NULL;
  if (lodestone_get_api(LODESTONE_API_VERSION_MAJOR, LODESTONE_API_VERSION_MINOR, &api) != LODESTONE_OK) return 1;
  printf("consumer: Lodestone %s, API %u.%u, %u node types\n", api->version_string(), api->major, api->minor,
         api->node_type_count());
  return 0;
}
