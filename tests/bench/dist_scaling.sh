#!/bin/sh
# Strong and weak scaling of the distributed field solve (docs/distributed.md):
# 1, 2 and 4 ranks (oversubscribed where the machine has fewer cores), PCMG,
# PCGAMG and hypre BoomerAMG. Usage: dist_scaling.sh BUILD_DIR [CSV]
set -eu
build=${1:?usage: dist_scaling.sh BUILD_DIR [CSV]}
csv=${2:-dist_scaling.csv}
bench="$build/tests/bench/lodestone-bench-dist-field"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1
echo "series,ranks,nodes,nodes_per_rank,pc,newton,cg,setup_s,solve_s,peak_rss_mb,converged" > "$csv"
for pc in mg gamg hypre; do
  # Strong: one 49^3 grid on 1, 2, 4 ranks.
  for r in 1 2 4; do
    mpirun -n $r --oversubscribe "$bench" --nodes 49 --pc $pc --series strong --csv "$csv"
  done
  # Weak: about 33^3 nodes per rank (33^3, 41^3, 53^3 on 1, 2, 4 ranks).
  set -- 1 33 2 41 4 53
  while [ $# -gt 0 ]; do
    mpirun -n "$1" --oversubscribe "$bench" --nodes "$2" --pc $pc --series weak --csv "$csv"
    shift 2
  done
done
echo "CSV written to $csv"
