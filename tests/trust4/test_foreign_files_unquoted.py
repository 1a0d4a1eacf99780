"""Trust round 4 (issue 42), item 11: a file that is not in the expected format (a link to
``/proc/self/environ``, a binary, a text whose first line is a secret) is refused saying what was expected and
where, quoting nothing of it."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from isolator import ScenarioError
from isolator.calibration.records import read_record
from isolator.scenario.tables import read_csv_columns

SECRET = st.text("QXZ0123456789", min_size=8, max_size=40)
FIXTURES = [HealthCheck.function_scoped_fixture]


def _readers(path: Path) -> list:
    return [lambda: read_record(path, ["a-z"]),
            lambda: read_csv_columns(path, "profile.file", ("t", "q")),
            lambda: read_csv_columns(path, "forces", ("t",), ("z1",)),
            lambda: read_csv_columns(path, "spectrum", ("frequency", "psd"), exact=True)]


def _refuses_without_quoting(path: Path, secret: str) -> None:
    for read in _readers(path):
        with pytest.raises(ScenarioError) as error:
            read()
        message = str(error.value)
        for i in range(len(secret) - 4):
            assert secret[i:i + 5] not in message.replace(str(path), ""), message
        assert "expected" in message or "must be" in message, message


@given(secret=SECRET, separator=st.sampled_from(["\x00", "\n", ",", "\x1b", "="]))
@settings(suppress_health_check=FIXTURES, max_examples=40)
def test_a_file_that_is_no_table_is_refused_without_a_word_of_it(tmp_path, secret, separator):
    path = tmp_path / "record.csv"
    path.write_text(f"AWS_KEY={secret}{separator}HOME=/root{separator}x=1\n1,2\n3,4\n")
    _refuses_without_quoting(path, secret)


@pytest.mark.skipif(not Path("/proc/self/environ").exists(), reason="Linux only")
def test_a_link_to_the_environment_quotes_none_of_it(tmp_path, monkeypatch):
    monkeypatch.setenv("AAAA_SECRET_FIRST", "hunter2-hunter2")  # (the environ of this process, whatever order)
    link = tmp_path / "floor.csv"
    link.symlink_to("/proc/self/environ")
    environ = Path("/proc/self/environ").read_bytes().decode(errors="replace")
    for read in _readers(link):
        with pytest.raises(ScenarioError) as error:
            read()
        message = str(error.value)
        assert "control character 0x00" in message, message
        assert environ[:8] not in message
        assert "hunter2" not in message
    assert os.environ["AAAA_SECRET_FIRST"]


@given(secret=SECRET)
@settings(suppress_health_check=FIXTURES, max_examples=10, deadline=None)
def test_a_universal_file_that_is_not_one_quotes_none_of_it(tmp_path, secret):
    path = tmp_path / "record.uff"
    path.write_text(f"    -1\n    58\nAWS_KEY={secret}\n{secret} {secret}\n    -1\n")
    with pytest.raises(ScenarioError) as error:
        read_record(path, ["a-z"], uff={"a-z": (1, "Z")})
    message = str(error.value).replace(str(path), "")
    assert "expected UFF datasets 58" in message, message
    for i in range(len(secret) - 4):
        assert secret[i:i + 5] not in message, message
