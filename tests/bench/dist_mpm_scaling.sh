#!/bin/sh
# Strong and weak scaling of the distributed MPM (docs/distributed.md): 1, 2
# and 4 ranks of one thread each (oversubscribed where the machine has fewer
# cores). Usage: dist_mpm_scaling.sh BUILD_DIR [CSV]
set -eu
build=${1:?usage: dist_mpm_scaling.sh BUILD_DIR [CSV]}
csv=${2:-dist_mpm_scaling.csv}
bench="$build/tests/bench/lodestone-bench-dist-mpm"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1
echo "series,ranks,nodes,cells,particles,largest_rank_particles,substep_s,rank_ns_per_particle_substep,migrations_per_substep,rss_mb,setup_peak_rss_mb" > "$csv"
# Strong: 1e6 particles in a 129^3 grid on 1, 2, 4 ranks.
for r in 1 2 4; do
  mpirun -n $r --oversubscribe "$bench" --nodes 129 --particles 1e6 --substeps 10 --series strong --csv "$csv"
done
# Weak: 2.5e5 particles and about 2.6e5 cells per rank (65^3, 81^3, 103^3).
set -- 1 65 2.5e5 2 81 5e5 4 103 1e6
while [ $# -gt 0 ]; do
  mpirun -n "$1" --oversubscribe "$bench" --nodes "$2" --particles "$3" --substeps 10 --series weak --csv "$csv"
  shift 3
done
echo "CSV written to $csv"
