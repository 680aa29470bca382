# Sourced by the bench scripts: the environment `scan2cad` gives its stages (README, "Using it":
# transparent huge pages for malloc, s2c::request_huge_pages_for_children), exported here for
# ours and the peers alike, including the benchmarks that run our code in their own process.
[[ "${GLIBC_TUNABLES:-}" == *glibc.malloc.hugetlb* ]] ||
  export GLIBC_TUNABLES="${GLIBC_TUNABLES:+$GLIBC_TUNABLES:}glibc.malloc.hugetlb=1"
