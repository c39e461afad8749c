#!/usr/bin/env bash
# Sourced by the build scripts: when ccache is installed, compile through it and make its hashes
# independent of where the clone lives, so a fresh clone (CI) reuses the objects of any earlier
# build of the same sources with the same flags on this machine. Sets ccache_args for cmake.
#   base_dir     absolute paths under the clone's parent folder hash as relative paths;
#   hash_dir     off: the working directory is not hashed (it only feeds the debug info's
#                compilation directory, -g1 line tables of the sanitizer builds);
#   sloppiness   the tests' precompiled header and __TIME__-free sources; headers freshly
#                checked out are not "too new" to cache.
# SVSLAM_CCACHE=0 builds without it.
ccache_args=()
if [ "${SVSLAM_CCACHE:-1}" != "0" ] && command -v ccache > /dev/null 2>&1; then
  CCACHE_BASEDIR="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
  export CCACHE_BASEDIR
  export CCACHE_NOHASHDIR=1
  export CCACHE_SLOPPINESS=${CCACHE_SLOPPINESS:-pch_defines,time_macros,include_file_mtime,include_file_ctime}
  ccache_args=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
