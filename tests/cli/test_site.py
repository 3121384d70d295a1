"""asekit.cli.site: the sphinx-build wrapper and its offline checker of the built site, on small
sites written here (building the real site executes every notebook and takes minutes: .ci/run
does it, with ``sphinx-build -W`` and ``--check-only``)."""

import pytest

from asekit.cli import site


def _write(path, text=""):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def _sound_site(root):
    _write(root / "index.html",
           '<html><head><link rel="stylesheet" href="_static/s.css">'
           '<script src="_static/mathjax/MathJax.js?config=TeX-AMS-MML_HTMLorMML-full"></script>'
           '</head><body><h1 id="top">x</h1><a href="#top">top</a>'
           '<a href="guide/page.html#sec">guide</a><a href="guide/">folder</a>'
           '<a href="https://doi.org/10.2514/3.45">a paper (a link, not a load)</a>'
           '<img src="_images/fig.png" alt="a figure"></body></html>')
    _write(root / "guide" / "page.html", '<section id="sec"><a href="../index.html">up</a>'
           '</section>')
    _write(root / "guide" / "index.html", "<p>folder page</p>")
    _write(root / "_images" / "fig.png")
    _write(root / "_static" / "font.woff2")
    _write(root / "_static" / "s.css", "@font-face { src: url('font.woff2'); }\n"
           "a { background: url(data:image/png;base64,AAAA); }")
    for f in site.MATHJAX_FILES:
        _write(root / f)
    # a theme's template in _static is not a page (its links are Jinja expressions)
    _write(root / "_static" / "macros.html", "<script src=\"{{ pathto('x.js', 1) }}\"></script>")
    return root


def test_a_sound_site_has_no_problem(tmp_path):
    assert site.check_site(_sound_site(tmp_path)) == []


def test_every_kind_of_problem_is_one_line(tmp_path):
    root = _sound_site(tmp_path)
    _write(root / "index.html",
           '<html><head><link rel="stylesheet" href="https://cdn.example/theme.css">'
           '<script src="//cdn.example/require.js"></script>'
           '<script src="_static/mathjax/MathJax.js"></script></head>'
           '<body><a href="gone.html">gone</a><a href="guide/page.html#nope">bad anchor</a>'
           '<img src="_images/missing.png"></body></html>')
    _write(root / "_static" / "s.css", "@import 'https://fonts.example/f.css';\n"
           "b { background: url(\"missing.png\"); }")
    (root / site.MATHJAX_FILES[2]).unlink()
    problems = site.check_site(root)
    assert problems == [
        "index.html: loads https://cdn.example/theme.css from the network",
        "index.html: loads //cdn.example/require.js from the network",
        "index.html: missing _images/missing.png",
        "index.html: broken link gone.html",
        "index.html: broken link guide/page.html#nope (no id 'nope' in guide/page.html)",
        "_static/s.css: loads https://fonts.example/f.css from the network",
        "_static/s.css: missing missing.png",
        f"offline MathJax: missing {site.MATHJAX_FILES[2]}",
    ]


def test_check_only_exit_status(tmp_path, capsys):
    assert site.main([str(_sound_site(tmp_path / "pages")), "--check-only"]) == 0
    _sound_site(tmp_path / "out" / "html")    # build()'s folder: the pages in OUT/html
    assert site.main([str(tmp_path / "out"), "--check-only"]) == 0
    capsys.readouterr()
    _write(tmp_path / "pages" / "index.html", '<a href="gone.html">gone</a>')
    assert site.main([str(tmp_path / "pages"), "--check-only"]) == 1
    assert capsys.readouterr().err == "error: index.html: broken link gone.html\n"
    assert site.main([str(tmp_path / "nothing"), "--check-only"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "outdir must be a built site" in err


def test_without_the_sources_one_line_and_exit_2(tmp_path, monkeypatch, capsys):
    # an installed wheel: the package without docs/ and notebooks/ beside it
    monkeypatch.setattr(site, "ROOT", tmp_path)
    assert site.main([str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "documentation sources are not here" in err
    assert "pip install -e '.[docs]'" in err
    assert not (tmp_path / "out").exists()              # nothing written, no empty index
    _write(tmp_path / "docs" / "conf.py")
    (tmp_path / "notebooks").mkdir()
    with pytest.raises(FileNotFoundError, match="no notebook"):
        site.docs_sources(tmp_path)


def test_bad_arguments_exit_2(tmp_path, capsys):
    f = _write(tmp_path / "file", "x")
    assert site.main([str(f)]) == 2
    assert "outdir must be a directory" in capsys.readouterr().err
    assert site.main([str(tmp_path / "out"), "--timeout", "0"]) == 2
    assert "--timeout must be > 0 s" in capsys.readouterr().err


def test_the_checkout_has_the_sources():
    docs, notebooks = site.docs_sources()
    assert (docs / "conf.py").is_file() and len(list(notebooks.glob("*.ipynb"))) >= 11
