"""The laboratory configuration ``imucalib.toml`` (docs/configuration.md): where it is found,
its defaults, and its one-line refusals naming the file and the field."""

from __future__ import annotations

from pathlib import Path

import pytest

from imucalib import config as cfg
from imucalib.errors import ConfigurationError

FULL = """
[laboratory]
name = "Inertial Lab"
address = "1 Example Street, Town"
accreditation = "ISO/IEC 17025, XY-123"

[site]
latitude_deg = 48.1
height_m = 519.0
gravity_mps2 = 9.80753

[records]
database = "lab.db"

[operator]
default = "J. Doe"

[certificate]
show_budget = false
statements = ["Not to be reproduced except in full."]
"""


@pytest.fixture
def nowhere(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """No configuration anywhere: no $IMUCALIB_CONFIG, an empty working folder and user dir."""
    monkeypatch.delenv(cfg.ENV_VAR, raising=False)
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    monkeypatch.setattr(cfg, "_user_file", lambda: tmp_path / "user" / cfg.CONFIG_FILE)
    return tmp_path


def test_no_file_means_the_defaults(nowhere):
    lab = cfg.load_config()
    assert lab.source == ""
    assert (lab.laboratory.name, lab.laboratory.address) == ("not stated", "not stated")
    assert lab.laboratory.accreditation == "not accredited"
    assert lab.site.latitude_deg is None and lab.records.database == ""
    assert lab.operator.default == "" and lab.certificate.show_budget is True


def test_every_field_is_read(nowhere):
    path = nowhere / "lab.toml"
    path.write_text(FULL, encoding="utf-8")
    lab = cfg.load_config(path)
    assert lab.source == str(path)
    assert lab.laboratory.name == "Inertial Lab"
    assert lab.laboratory.accreditation == "ISO/IEC 17025, XY-123"
    assert (lab.site.latitude_deg, lab.site.height_m, lab.site.gravity_mps2) == (48.1, 519.0,
                                                                                 9.80753)
    assert lab.records.database == str(nowhere / "lab.db")  # relative: beside the file
    assert lab.operator.default == "J. Doe"
    assert lab.certificate.show_budget is False
    assert lab.certificate.statements == ("Not to be reproduced except in full.",)


def test_where_it_is_found_named_then_env_then_working_folder_then_user(nowhere, monkeypatch):
    user = nowhere / "user" / cfg.CONFIG_FILE
    user.parent.mkdir()
    user.write_text('[laboratory]\nname = "user"\n', encoding="utf-8")
    assert cfg.load_config().laboratory.name == "user"
    Path(cfg.CONFIG_FILE).write_text('[laboratory]\nname = "cwd"\n', encoding="utf-8")
    assert cfg.load_config().laboratory.name == "cwd"
    env = nowhere / "env.toml"
    env.write_text('[laboratory]\nname = "env"\n', encoding="utf-8")
    monkeypatch.setenv(cfg.ENV_VAR, str(env))
    assert cfg.load_config().laboratory.name == "env"
    named = nowhere / "named.toml"
    named.write_text('[laboratory]\nname = "named"\n', encoding="utf-8")
    with cfg.use_config(named):  # what --config FILE does for one command
        assert cfg.load_config().laboratory.name == "named"
    assert cfg.load_config().laboratory.name == "env"  # and only inside it
    assert cfg.load_config(named).laboratory.name == "named"


@pytest.mark.parametrize(("text", "field"), [
    ('[site]\nlatitude_deg = "north"\n', "[site] latitude_deg"),
    ("[site]\nlatitude_deg = 123.0\n", "[site] latitude_deg"),
    ("[site]\ngravity_mps2 = 98.1\n", "[site] gravity_mps2"),
    ("[laboratory]\nnmae = 'x'\n", "[laboratory] nmae: unknown field"),
    ("[certificat]\nshow_budget = true\n", "[certificat]: unknown field"),
    ('[certificate]\nshow_budget = "sometimes"\n', "[certificate] show_budget"),
    ('source = "x"\n', "[source]: unknown field"),
    ("[laboratory\n", "not valid TOML"),
])
def test_a_bad_field_is_refused_in_one_line_naming_the_file_and_the_field(nowhere, text, field):
    path = nowhere / "bad.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ConfigurationError) as info:
        cfg.load_config(path)
    message = str(info.value)
    assert message.startswith(f"laboratory configuration {path}: ")
    assert field in message and "\n" not in message


def test_a_named_file_must_exist(nowhere, monkeypatch):
    with pytest.raises(ConfigurationError, match="no such file"):
        cfg.load_config(nowhere / "missing.toml")
    monkeypatch.setenv(cfg.ENV_VAR, str(nowhere / "missing.toml"))
    with pytest.raises(ConfigurationError, match=r"missing\.toml: no such file"):
        cfg.load_config()
    with pytest.raises(ConfigurationError, match="no such file"):
        with cfg.use_config(nowhere / "missing.toml"):
            pass


def test_the_records_database_default_comes_from_the_configuration(nowhere, monkeypatch):
    from imucalib.records.engine import resolve_url

    path = nowhere / "lab.toml"
    path.write_text(FULL, encoding="utf-8")
    monkeypatch.delenv("IMUCALIB_DB", raising=False)
    with cfg.use_config(path):
        assert resolve_url() == f"sqlite:///{nowhere / 'lab.db'}"
        assert resolve_url("other.db").endswith("/other.db")  # --db wins
        monkeypatch.setenv("IMUCALIB_DB", str(nowhere / "env.db"))
        assert resolve_url().endswith("/env.db")  # and $IMUCALIB_DB


def test_the_certificate_takes_the_laboratory_from_the_configuration(nowhere):
    from imucalib.exports.report import laboratory_facts

    path = nowhere / "lab.toml"
    path.write_text(FULL, encoding="utf-8")
    facts = laboratory_facts(cfg.load_config(path), customer="ACME")
    assert (facts.laboratory, facts.address) == ("Inertial Lab", "1 Example Street, Town")
    assert facts.accreditation == "ISO/IEC 17025, XY-123" and facts.customer == "ACME"
    assert dict(facts.site) == {"latitude": "48.1°", "height": "519 m",
                                "local gravity": "9.807530 m/s²"}
    assert facts.show_budget is False
    assert facts.statements == ("Not to be reproduced except in full.",)
    default = laboratory_facts()
    assert (default.laboratory, default.accreditation) == ("not stated", "not accredited")
