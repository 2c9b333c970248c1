"""Fixture of cmake/check_test_temp_paths.cmake (never run): findings expected at lines 6 and 7 only."""
import tempfile


def test_shared():
    shared = tempfile.gettempdir() + "/jointsim_shared"
    other = '/tmp/jointsim_other'
    allowed = "/tmp/evil"  # tmp-path-ok: hostile input, never written
    return shared, other, allowed
