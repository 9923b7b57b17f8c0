"""A signal during the creation of a temporary is held back until the clean-up knows the file."""
import os
import signal

import pytest

from crfmap.io import atomic


def test_a_signal_while_a_temporary_is_made_is_raised_after_it_is_registered(tmp_path):
    made = []
    with atomic.signals_raise():
        with pytest.raises(atomic.Interrupted):
            with atomic._signals_deferred():
                os.kill(os.getpid(), signal.SIGHUP)  # arrives "between mkstemp and the bookkeeping"
                made.append("registered")  # still runs: the handler only noted the signal
    assert made == ["registered"]


def test_the_atomic_write_leaves_nothing_when_interrupted(tmp_path):
    target = tmp_path / "out.txt"
    with atomic.signals_raise():
        with pytest.raises(atomic.Interrupted):
            with atomic.atomic_path(target) as tmp:
                tmp.write_text("half")
                os.kill(os.getpid(), signal.SIGTERM)
                tmp.write_text("never reached")
    assert list(tmp_path.iterdir()) == []
