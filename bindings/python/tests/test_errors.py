"""Bad input raises ehservo.ScenarioError (a ValueError) with the CLI's
message, naming the key."""

import pytest

import ehservo

FIG2 = "scenarios/paper/fig2.toml"


def cli_error(cli, *args):
    p = cli(*args, check=False)
    assert p.returncode == 2, p.stderr
    line = p.stderr.strip().splitlines()[-1]
    assert line.startswith("error: ")
    return line[len("error: "):]


def test_unknown_key_in_an_override(cli, repo, tmp_path, monkeypatch):
    monkeypatch.chdir(repo)
    with pytest.raises(ehservo.ScenarioError) as e:
        ehservo.run(FIG2, controller__gama1=3)
    assert isinstance(e.value, ValueError)
    assert e.value.key == "controller.gama1"
    assert "unknown field `gama1`" in e.value.reason
    want = cli_error(cli, "run", FIG2, "--set", "controller.gama1=3", "--out", tmp_path / "o")
    assert str(e.value) == want


def test_bad_value_in_a_file_names_key_line_and_column(cli, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[plant.params]\nJt = -0.05\n")
    with pytest.raises(ehservo.ScenarioError) as e:
        ehservo.run(bad)
    assert (e.value.key, e.value.line, e.value.column) == ("plant.params.Jt", 2, 6)
    assert e.value.reason == "must be finite and > 0 (got -0.05)"
    assert str(e.value) == cli_error(cli, "run", bad, "--out", tmp_path / "o")


def test_wrong_type_and_unknown_kind(repo, monkeypatch):
    monkeypatch.chdir(repo)
    with pytest.raises(ehservo.ScenarioError, match="controller.gamma1"):
        ehservo.run(FIG2, controller__gamma1="fast")
    with pytest.raises(ehservo.ScenarioError, match="unknown controller kind `lqr`"):
        ehservo.Controller(FIG2, controller__kind="lqr")


def test_missing_file_and_bad_toml_text(tmp_path):
    with pytest.raises(ehservo.ScenarioError, match="nope.toml"):
        ehservo.run(tmp_path / "nope.toml")
    with pytest.raises(ehservo.ScenarioError, match="TOML syntax error") as e:
        ehservo.run("name = \n")
    assert e.value.file == "<string>"


def test_bad_study(cli, tmp_path):
    study = tmp_path / "s.toml"
    study.write_text('name = "s"\nbase = "nope.toml"\n')
    with pytest.raises(ehservo.ScenarioError, match="base") as e:
        ehservo.sweep(study)
    assert str(e.value) == cli_error(cli, "sweep", study, "--out", tmp_path / "o")
