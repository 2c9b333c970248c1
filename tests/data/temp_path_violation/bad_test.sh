#!/usr/bin/env bash
# Fixture of cmake/check_test_temp_paths.cmake (never run): a finding expected at line 4 only.
good="$(mktemp -d "${TMPDIR:-/tmp}/jointsim.XXXXXX")"
out=/tmp/jointsim_shared
echo "$good $out"
