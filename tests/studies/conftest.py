"""The peer renderer's fixture, shared by the peer tests: Mitsuba 3 + mitransient must run
here; without it the tests skip, except under CI (environment variable CI set), where they
fail: a peer check that silently skips in CI checks nothing."""

from __future__ import annotations

import os

import pytest

from meshladar.studies import peer


@pytest.fixture(scope="module")
def renderer():
    ok, msg = peer.available(reason=True)
    if not ok:
        if os.environ.get("CI"):
            pytest.fail(msg)
        pytest.skip(msg)
