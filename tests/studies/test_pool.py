"""surrogate.data.pool.process_map: ordered results in and out of process, one BLAS thread per
worker, errors surface, bad worker counts are refused."""

import io
import os

import pytest

from surrogate.data.pool import THREAD_VARS, process_map


def _square(x):
    return x * x


def _blas_env(_):
    return {k: os.environ.get(k) for k in THREAD_VARS}


def _fail_on_three(x):
    if x == 3:
        raise ArithmeticError(f"item {x}")
    return x


@pytest.mark.parametrize("workers", [1, 2])
def test_results_come_back_in_input_order(workers):
    items = list(range(12, 0, -1))
    assert process_map(_square, items, workers=workers) == [x * x for x in items]


def test_workers_run_with_one_blas_thread_and_the_parent_env_is_restored(monkeypatch):
    for k in THREAD_VARS:
        monkeypatch.delenv(k, raising=False)
    envs = process_map(_blas_env, range(3), workers=2)
    assert all(e == dict.fromkeys(THREAD_VARS, "1") for e in envs)
    assert all(k not in os.environ for k in THREAD_VARS)


def test_a_user_set_thread_count_is_kept(monkeypatch):
    monkeypatch.setenv("OMP_NUM_THREADS", "3")
    (env, _) = process_map(_blas_env, range(2), workers=2)
    assert env["OMP_NUM_THREADS"] == "3"


@pytest.mark.parametrize("workers", [1, 2])
def test_the_first_error_is_raised(workers):
    with pytest.raises(ArithmeticError, match="item 3"):
        process_map(_fail_on_three, range(6), workers=workers)


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_goes_to_a_terminal_on_stderr(monkeypatch, capsys):
    term = _Terminal()
    monkeypatch.setattr("sys.stderr", term)
    assert process_map(_square, [1, 2], workers=1, desc="squares") == [1, 4]
    assert "squares" in term.getvalue() and "2/2" in term.getvalue()
    assert capsys.readouterr().out == ""


def test_no_progress_bar_in_logs_and_pipes(capsys):
    assert process_map(_square, [1, 2], workers=1, desc="squares") == [1, 4]
    assert capsys.readouterr() == ("", "")


@pytest.mark.parametrize("workers", [0, -1, 257, 1.5, True])
def test_bad_worker_counts_are_refused(workers):
    with pytest.raises(ValueError, match="1 <= workers <= 256"):
        process_map(_square, [1], workers=workers)


def test_empty_input_gives_an_empty_list():
    assert process_map(_square, [], workers=2) == []
