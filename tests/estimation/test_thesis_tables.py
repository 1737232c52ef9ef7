"""The thesis result tables ship as a data file read by the package (estimation/thesis_tables.csv)."""
from importlib.resources import files

import pytest

from visland.estimation.study import STUDIES
from visland.estimation.thesis_tables import THESIS_CONDITIONS, THESIS_DATA, THESIS_TABLES, thesis_value


def test_the_data_file_ships_inside_the_package():
    text = files("visland.estimation").joinpath(THESIS_DATA).read_text(encoding="utf-8")
    assert text.splitlines()[0] == "table,condition,features,observer,metric,value"
    assert len(THESIS_TABLES) == len(text.splitlines()) - 1 == 280     # one figure per row, none twice


def test_figures_quoted_in_the_readme_read_back():
    # thesis Table 5.6 (1 px noise, CCPI at 100 ft over the eight scenarios) and 5.16 (with detection)
    assert thesis_value("5.6", "ccpi-hg-2p", "mean_err_100ft_m_all8") == pytest.approx(0.0991)
    assert thesis_value("5.6", "ccpi-hg-2p", "std_err_100ft_m_all8") == pytest.approx(0.0456)
    assert thesis_value("5.16", "cccs-2p", "mean_err_100ft_m_all8") == pytest.approx(0.74)
    assert thesis_value("5.16", "cccs-2p", "std_err_100ft_m_all8") == pytest.approx(0.64)
    assert THESIS_CONDITIONS["5.6"] == ("1 px Gaussian noise", "2 points")
    assert thesis_value("5.6", "ekf-2l", "mean_err_100ft_m_all8") is None     # the thesis has no such cell


def test_every_study_compares_with_a_table_of_the_file():
    tables = {spec.thesis_table for spec in STUDIES.values() if spec.thesis_table}
    assert tables and tables <= set(THESIS_CONDITIONS)
