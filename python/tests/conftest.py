"""Shared fixtures: the repository's models, and scratch copies of them."""

import pathlib
import shutil

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
MODELS = REPO / "models"


@pytest.fixture
def project(tmp_path):
    """A scratch project holding a copy of models/ (so saves never touch the repo)."""
    (tmp_path / "fitup.toml").write_text("# scratch project of the Python tests\n")
    shutil.copytree(MODELS, tmp_path / "models")
    return tmp_path
