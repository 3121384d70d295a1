"""asekit.cli.site: the parts that need no kernel (building the site executes every notebook; the
figure test, tests/reproduction/test_notebook_figures.py, covers execution with the inline backend)."""

import pytest

from asekit.cli import site


def test_chapter_notebooks_in_reading_order():
    names = [p.stem for p in site.chapter_notebooks()]
    assert names[:6] == list(site.ORDER)
    assert [p.stem for p in site.chapter_notebooks(["ch5_aeroservoelasticity", "ch2_theory"])] \
        == ["ch2_theory", "ch5_aeroservoelasticity"]
    with pytest.raises(ValueError, match="unknown notebook"):
        site.chapter_notebooks(["ch9_nope"])


def test_links_between_notebooks_point_to_pages():
    text = ('<a href="ch3_flutter.ipynb">next</a> <a href="./ch2_theory.ipynb#top">prev</a> '
            '<a href="https://example.org/x.ipynb">other</a>')
    out = site._rewrite_links(text)
    assert 'href="ch3_flutter.html"' in out and 'href="ch2_theory.html#top"' in out
    assert "https://example.org/x.ipynb" in out


def test_outdir_must_not_be_a_file(tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    with pytest.raises(ValueError, match="outdir"):
        site.build_site(f, only=["ch2_theory"])
