/*
 * Lodestone plugin: the stable C ABI (C99 and C++).
 *
 * One exported symbol, lodestone_get_api(), hands out a versioned table of
 * function pointers. Everything else is reached through that table, so a host
 * can dlopen() liblodestone_plugin.so, look up one symbol and never link
 * against Lodestone's C++ code. See docs/plugin.md.
 *
 * Versioning. The table has a major and a minor version. A host asks for the
 * (major, minor) it was compiled against (LODESTONE_API_VERSION_MAJOR/MINOR);
 * the library grants it when the majors are equal and the library's minor is
 * >= the requested minor. Within one major, minors only append functions at
 * the end of the table and fields at the end of the structs that carry a
 * struct_size, so a table of minor m is a valid prefix of any later minor.
 * Anything else is refused with LODESTONE_ERROR_VERSION and a message naming
 * both versions (lodestone_get_api writes it to the thread's last error).
 *
 * Handles. lodestone_context, lodestone_stage, lodestone_fields and
 * lodestone_network are opaque. Every object is created by a *_create function
 * and released by the matching *_destroy (destroying NULL is a no-op).
 * A handle is an id, not the object's address: a handle that is no longer
 * live (destroyed once already, say), one of another kind and a value the
 * library never handed out are told apart from live handles and refused with
 * LODESTONE_ERROR_INVALID_HANDLE by every function, *_destroy included, even
 * after the library has created new objects meanwhile.
 * A stage, a field set or a network belongs to the context it was created in
 * and must be destroyed before it. Pointers passed in (particles, grids,
 * strings) are only read during the call; nothing keeps them. Buffers a
 * function writes into are owned by the caller. Strings the library returns
 * (messages, names, help) are owned by the library: status_string and node
 * metadata live as long as the library is loaded; a last-error string until
 * the next failing call on the same thread (and context).
 *
 * Errors. Every function returns a lodestone_status (LODESTONE_OK = 0) or, for
 * the few that cannot fail, a value. On failure the message (naming the bad
 * argument and value) is stored as the thread's last error
 * (thread_last_error) and, when a context is known, as that context's last
 * error for the calling thread (context_last_error). No C++ exception ever
 * crosses this interface: every entry catches everything (including
 * std::bad_alloc, reported as LODESTONE_ERROR_OUT_OF_MEMORY).
 *
 * Threads. Functions on different objects may run concurrently on different
 * threads (two stages stepped on two threads give the same results as a
 * serial run). One object (a stage, a field set, a network) is externally
 * synchronized: calls on it must not overlap. A context may be shared by
 * threads: creating and destroying objects in it and reading its last error
 * are internally locked, and its last error is kept per thread. Field sets are
 * only read by stage_run and may be shared by stages running concurrently as
 * long as nobody modifies them meanwhile. The library parallelizes inside a
 * call with oneTBB.
 *
 * Units are SI throughout: m, s, A/m, T, N, kg/m^3.
 */
#ifndef LODESTONE_PLUGIN_LODESTONE_H
#define LODESTONE_PLUGIN_LODESTONE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_WIN32)
#define LODESTONE_EXPORT __declspec(dllexport)
#else
#define LODESTONE_EXPORT __attribute__((visibility("default")))
#endif

#define LODESTONE_API_VERSION_MAJOR 1
#define LODESTONE_API_VERSION_MINOR 1

/* ---- status codes ------------------------------------------------------ */
typedef int32_t lodestone_status;
#define LODESTONE_OK 0
#define LODESTONE_ERROR_INVALID_ARGUMENT 1 /* a value out of range, a bad size or stride */
#define LODESTONE_ERROR_NULL_HANDLE 2      /* a required handle or pointer was NULL */
#define LODESTONE_ERROR_VERSION 3          /* requested API version not provided */
#define LODESTONE_ERROR_NOT_BUILT 4        /* the feature needs a component not built (e.g. OpenVDB) */
#define LODESTONE_ERROR_OUT_OF_MEMORY 5    /* estimated too large for memory (sized message), or std::bad_alloc */
#define LODESTONE_ERROR_NOT_READY 6        /* e.g. reading fields of a stage that has not run */
#define LODESTONE_ERROR_BUFFER_TOO_SMALL 7 /* the caller's buffer cannot hold the result */
#define LODESTONE_ERROR_NOT_FOUND 8        /* no node type, node, parameter or port of that name */
#define LODESTONE_ERROR_IO 9               /* a file could not be read or written */
#define LODESTONE_ERROR_COOK_FAILED 10     /* a node's cook threw: the message names the node */
#define LODESTONE_ERROR_INTERNAL 11        /* any other failure inside the library */
#define LODESTONE_ERROR_INVALID_HANDLE 12  /* a handle already destroyed, of another kind, or never handed out */

/* ---- plain types --------------------------------------------------------- */
typedef struct lodestone_context lodestone_context;
typedef struct lodestone_stage lodestone_stage;
typedef struct lodestone_fields lodestone_fields;
typedef struct lodestone_network lodestone_network;

/* Element type of a caller's array. */
typedef int32_t lodestone_scalar_type;
#define LODESTONE_FLOAT32 0
#define LODESTONE_FLOAT64 1

/* A node-centred grid: node (i,j,k) at origin + dx*(i,j,k); arrays x fastest. */
typedef struct lodestone_grid {
  double origin[3]; /* m */
  double dx;        /* m, > 0 */
  int32_t dims[3];  /* nodes per axis, >= 2 */
} lodestone_grid;

/* Material points as seen by the stage. Particle p's position is the three
   consecutive scalars at (char*)positions + p*position_stride; its count n_p
   (micro-particles, >= 0) the scalar at (char*)counts + p*count_stride. A
   stride of 0 means tightly packed (3 or 1 scalars). */
typedef struct lodestone_particles {
  uint32_t struct_size; /* sizeof(lodestone_particles) */
  lodestone_scalar_type type;
  size_t count;
  const void* positions;  /* m */
  size_t position_stride; /* bytes */
  const void* counts;
  size_t count_stride; /* bytes */
} lodestone_particles;

/* A caller's output array of 3-vectors: element p at (char*)data + p*stride. */
typedef struct lodestone_vec3_out {
  uint32_t struct_size; /* sizeof(lodestone_vec3_out) */
  lodestone_scalar_type type;
  void* data;
  size_t stride;   /* bytes, 0 = packed */
  size_t capacity; /* elements available */
} lodestone_vec3_out;

/* Magnetization laws. */
#define LODESTONE_LAW_NONE 0
#define LODESTONE_LAW_LINEAR 1   /* M = chi (n/n0) H */
#define LODESTONE_LAW_LANGEVIN 2 /* micro-particles of moment m at temperature T */
#define LODESTONE_LAW_PAPER 3    /* Sun et al. 2021, Table 2 (Langevin) */

#define LODESTONE_BOUNDARY_OPEN 0   /* far-field potential on the outer nodes */
#define LODESTONE_BOUNDARY_SHIELD 1 /* Neumann wall (superconducting box) */

#define LODESTONE_OUT_OF_GRID_THROW 0 /* a particle outside the grid is an error */
#define LODESTONE_OUT_OF_GRID_SKIP 1  /* ignored and counted in the report */

/* Everything a stage is made from. Fill with stage_params_default first. */
typedef struct lodestone_stage_params {
  uint32_t struct_size;          /* sizeof(lodestone_stage_params) */
  int32_t law;                   /* LODESTONE_LAW_* */
  double moment;                 /* A*m^2, Langevin micro-particle moment */
  double temperature;            /* K, Langevin */
  double chi;                    /* linear susceptibility of the bulk material, >= 0 (checked for every law) */
  double number_density;         /* n0, micro-particles per m^3 of bulk material (0: the paper's) */
  lodestone_grid grid;           /* the stage's grid before padding */
  int32_t padding;               /* cells of free space added on every side (0..64) */
  double tolerance;              /* relative Newton residual, in [1e-14, 0.1] (default 1e-8) */
  int32_t max_newton_iterations; /* 1..1000 */
  int32_t boundary;              /* LODESTONE_BOUNDARY_* */
  int32_t out_of_grid;           /* LODESTONE_OUT_OF_GRID_* */
  int32_t warm_start;            /* nonzero: start each solve from the last potential */
} lodestone_stage_params;

/* Outcome of one stage run. */
typedef struct lodestone_report {
  uint32_t struct_size; /* sizeof(lodestone_report) */
  int32_t converged;    /* nonzero when the solve converged (or was trivial) */
  int32_t solve_status; /* 0 converged, 1 trivial, 2 iteration cap, 3 line search, 4 linear solver, 5 non-finite, 6
                           cancelled */
  int32_t newton_iterations;
  int32_t cg_iterations;
  double relative_residual;
  double total_force[3]; /* N, sum of nodal forces */
  double total_count;    /* micro-particles on the grid */
  uint64_t particles_skipped;
  double seconds_transfer, seconds_solve, seconds_force, seconds_total; /* s */
} lodestone_report;

/* Fields a stage can hand back (one value or 3-vector per node). */
typedef int32_t lodestone_field_kind;
#define LODESTONE_FIELD_DENSITY 0       /* n, 1/m^3 (scalar) */
#define LODESTONE_FIELD_POTENTIAL 1     /* phi, A (scalar) */
#define LODESTONE_FIELD_APPLIED 2       /* H_ext, A/m, as the material sees it: inside a magnet,
                                           the field outside continued through its nearest face */
#define LODESTONE_FIELD_H 3             /* H, A/m (the true field, inside magnets too) */
#define LODESTONE_FIELD_M 4             /* M, A/m: the material's plus permanent magnets' own */
#define LODESTONE_FIELD_B 5             /* B = mu0 (H + M), T */
#define LODESTONE_FIELD_FORCE_DENSITY 6 /* t = div T, N/m^3 */
#define LODESTONE_FIELD_NODAL_FORCE 7   /* f, N */

/* Node metadata. */
typedef int32_t lodestone_param_type;
#define LODESTONE_PARAM_FLOAT 0
#define LODESTONE_PARAM_INT 1
#define LODESTONE_PARAM_BOOL 2
#define LODESTONE_PARAM_STRING 3
#define LODESTONE_PARAM_CHOICE 4
#define LODESTONE_PARAM_VEC3 5       /* also directions (normalised when set) */
#define LODESTONE_PARAM_FLOAT_LIST 6 /* set with network_set_json */

typedef struct lodestone_node_info {
  uint32_t struct_size;
  const char* type; /* e.g. "magnetic_force" */
  const char* label;
  const char* category;
  const char* help;
  uint32_t param_count, input_count, output_count;
} lodestone_node_info;

typedef struct lodestone_param_info {
  uint32_t struct_size;
  const char* name;
  const char* label;
  lodestone_param_type type;
  const char* unit; /* "" when dimensionless */
  const char* help;
  const char* default_text; /* the default as JSON text */
  double min, max;          /* range of numbers (-inf/inf when open-ended) */
  const char* choices;      /* CHOICE: allowed values separated by '|' ; "" otherwise */
} lodestone_param_info;

typedef struct lodestone_port_info {
  uint32_t struct_size;
  const char* name;
  const char* type; /* "particles", "material", "sources", "colliders", "density", "field", "forces", "simulation" */
  const char* help;
  int32_t optional; /* inputs: nonzero when the cook runs without it */
  int32_t multiple; /* inputs: nonzero when several connections merge */
} lodestone_port_info;

/* ---- the function table ---------------------------------------------- */
typedef struct lodestone_api {
  uint32_t struct_size; /* of the table the library filled */
  uint32_t major, minor;

  /* library */
  const char* (*version_string)(void);
  const char* (*status_string)(lodestone_status status);
  const char* (*thread_last_error)(void);
  int32_t (*has_vdb)(void); /* nonzero when VDB import/export is built */

  /* context */
  lodestone_status (*context_create)(lodestone_context** out);
  lodestone_status (*context_destroy)(lodestone_context* context);
  const char* (*context_last_error)(lodestone_context* context); /* this thread's; "" when none */

  /* applied-field sources (positions m, fields A/m, magnetization A/m, time scale none) */
  lodestone_status (*fields_create)(lodestone_context* context, lodestone_fields** out);
  lodestone_status (*fields_destroy)(lodestone_fields* fields);
  lodestone_status (*fields_add_uniform)(lodestone_fields* fields, const double H[3]);
  lodestone_status (*fields_add_dipole)(lodestone_fields* fields, const double position[3], const double moment[3]);
  /* Magnets: centre (m), axis (any length > 0; the magnetization points along it), magnetization (A/m). */
  lodestone_status (*fields_add_sphere_magnet)(lodestone_fields* fields, const double center[3], const double axis[3],
                                               double radius, double magnetization);
  lodestone_status (*fields_add_box_magnet)(lodestone_fields* fields, const double center[3], const double axis[3],
                                            const double half_size[3], double magnetization);
  lodestone_status (*fields_add_cylinder_magnet)(lodestone_fields* fields, const double center[3], const double axis[3],
                                                 double radius, double half_length, double magnetization);
  /* A vector grid of a .vdb file as H (A/m); LODESTONE_ERROR_NOT_BUILT without OpenVDB. */
  lodestone_status (*fields_add_vdb)(lodestone_fields* fields, const char* path, const char* grid_name);
  lodestone_status (*fields_count)(const lodestone_fields* fields, uint32_t* out);
  lodestone_status (*fields_evaluate)(const lodestone_fields* fields, const double x[3], double time, double H_out[3]);

  /* stage */
  lodestone_status (*stage_params_default)(lodestone_stage_params* params); /* params->struct_size must be set */
  lodestone_status (*stage_create)(lodestone_context* context, const lodestone_stage_params* params,
                                   lodestone_stage** out);
  lodestone_status (*stage_destroy)(lodestone_stage* stage);
  lodestone_status (*stage_grid)(const lodestone_stage* stage, lodestone_grid* out); /* after padding */
  /* Transfer + solve + force for particles at time t (s). report may be NULL. */
  lodestone_status (*stage_run_particles)(lodestone_stage* stage, const lodestone_particles* particles,
                                          const lodestone_fields* fields, double time, lodestone_report* report);
  /* Solve + force for a density n (1/m^3) given on the stage's grid (stage_grid;
     another grid is refused). */
  lodestone_status (*stage_run_density)(lodestone_stage* stage, const lodestone_grid* grid, const double* density,
                                        const lodestone_fields* fields, double time, lodestone_report* report);
  /* Conservative per-particle force (N) for the particles of the last run
     (stage_run_particles): another set (a different count, or positions or
     counts that differ from the last run's in a sampled fingerprint) gives
     LODESTONE_ERROR_INVALID_ARGUMENT. After stage_run_density any set whose
     deposit is that density is taken, unchecked. */
  lodestone_status (*stage_particle_forces)(const lodestone_stage* stage, const lodestone_particles* particles,
                                            lodestone_vec3_out* forces);
  /* Field samples at arbitrary points (quadratic B-spline): kind H (A/m) or FORCE_DENSITY (N/m^3). */
  lodestone_status (*stage_sample)(const lodestone_stage* stage, lodestone_field_kind kind,
                                   const lodestone_particles* points, lodestone_vec3_out* out);
  /* Copies a field of the last run into `out` (count values: nodes, or 3*nodes for vectors, x fastest, xyz
   * interleaved). */
  lodestone_status (*stage_read_field)(const lodestone_stage* stage, lodestone_field_kind kind,
                                       lodestone_scalar_type type, void* out, size_t count);
  lodestone_status (*stage_report)(const lodestone_stage* stage, lodestone_report* out);
  /* The last report as JSON, NUL-terminated; *needed gets the size incl. the NUL. */
  lodestone_status (*stage_report_json)(const lodestone_stage* stage, char* buffer, size_t capacity, size_t* needed);
  /* All fields of the last run to one .vdb file; LODESTONE_ERROR_NOT_BUILT without OpenVDB. */
  lodestone_status (*stage_export_vdb)(const lodestone_stage* stage, const char* path);

  /* node library */
  uint32_t (*node_type_count)(void);
  lodestone_status (*node_type_info)(uint32_t index, lodestone_node_info* out);
  lodestone_status (*node_param_info)(const char* type, uint32_t index, lodestone_param_info* out);
  lodestone_status (*node_input_info)(const char* type, uint32_t index, lodestone_port_info* out);
  lodestone_status (*node_output_info)(const char* type, uint32_t index, lodestone_port_info* out);

  /* networks: nodes named uniquely within a network */
  lodestone_status (*network_create)(lodestone_context* context, lodestone_network** out);
  lodestone_status (*network_destroy)(lodestone_network* network);
  lodestone_status (*network_add_node)(lodestone_network* network, const char* type, const char* name);
  lodestone_status (*network_set_float)(lodestone_network* network, const char* node, const char* param, double value);
  lodestone_status (*network_set_int)(lodestone_network* network, const char* node, const char* param, int64_t value);
  lodestone_status (*network_set_bool)(lodestone_network* network, const char* node, const char* param, int32_t value);
  lodestone_status (*network_set_string)(lodestone_network* network, const char* node, const char* param,
                                         const char* value); /* STRING and CHOICE */
  lodestone_status (*network_set_vec3)(lodestone_network* network, const char* node, const char* param,
                                       const double value[3]);
  /* Parameters from a JSON object text {"param": value, ...} read and checked as scene files are
     (syntax errors at line:column, duplicate and unknown keys refused, {"a": {"b": v}} sets a.b);
     when a value is refused, none is set. */
  lodestone_status (*network_set_json)(lodestone_network* network, const char* node, const char* json);
  lodestone_status (*network_connect)(lodestone_network* network, const char* from_node, const char* output,
                                      const char* to_node, const char* input);
  /* Cooks `node` and everything upstream that changed. */
  lodestone_status (*network_cook)(lodestone_network* network, const char* node);
  /* A cooked output as JSON (counts, totals, reports), NUL-terminated. */
  lodestone_status (*network_output_json)(lodestone_network* network, const char* node, const char* output,
                                          char* buffer, size_t capacity, size_t* needed);
  /* Positions (m) of a cooked "particles" or "simulation" output; *count gets the number. */
  lodestone_status (*network_read_positions)(lodestone_network* network, const char* node, const char* output,
                                             lodestone_vec3_out* out, size_t* count);

  /* ---- since minor 1 ---- */
  /* The number density n0 (micro-particles per m^3 of bulk material) of the
     stage's material, so that a host gives its particles n_p = n0 V_p
     (0 for LODESTONE_LAW_NONE). */
  lodestone_status (*stage_number_density)(const lodestone_stage* stage, double* n0);
  /* The host's own particles (positions, counts) as the parameters
     `positions` and `counts` of a "host_particles" node, copied; their
     volumes are n_p / n0 of the node's material unless its `volumes` are set. */
  lodestone_status (*network_set_particles)(lodestone_network* network, const char* node,
                                            const lodestone_particles* particles);
  /* Per-particle forces (N) of a cooked "forces" output (magnetic_force), in
     the order of its particles; *count gets the number. */
  lodestone_status (*network_read_forces)(lodestone_network* network, const char* node, const char* output,
                                          lodestone_vec3_out* out, size_t* count);
  /* A whole network from JSON text {"nodes": [{"name", "type", "params"}...],
     "connections": [{"from", "output", "to", "input"}...]} (docs/plugin.md),
     read as scene files are; on any error no network is made (*out = NULL). */
  lodestone_status (*network_create_from_json)(lodestone_context* context, const char* json,
                                               lodestone_network** out);
} lodestone_api;

/* The one exported symbol. On success *table points to a static table (never
   freed) whose major equals the requested major and whose minor is >= the
   requested minor. */
typedef lodestone_status (*lodestone_get_api_fn)(uint32_t major, uint32_t minor, const lodestone_api** table);
LODESTONE_EXPORT lodestone_status lodestone_get_api(uint32_t major, uint32_t minor, const lodestone_api** table);

#ifdef __cplusplus
}
#endif

#endif /* LODESTONE_PLUGIN_LODESTONE_H */
