"""benchmarks/report_surface.py: its sampling, its section surgery, and a --quick run."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from needs import absent

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import report_surface  # noqa: E402


def test_samples_are_centroids_of_congruent_subtriangles():
    for n in (1, 2, 4, 8):
        samples = report_surface.barycentric_samples(n)
        assert samples.shape == (n * n, 3)
        assert np.allclose(samples.sum(axis=1), 1.0)
        assert samples.min() > 0
        # Equal-area cells: their centroids average to the triangle's centroid.
        assert np.allclose(samples.mean(axis=0), 1 / 3)
        assert len(np.unique(np.round(samples, 12), axis=0)) == n * n
    # n = 2: the three corner triangles' centroids and the middle one's, by hand.
    expected = {(2 / 3, 1 / 6, 1 / 6), (1 / 6, 2 / 3, 1 / 6), (1 / 6, 1 / 6, 2 / 3), (1 / 3,) * 3}
    got = {tuple(np.round(row, 12)) for row in report_surface.barycentric_samples(2)}
    assert got == {tuple(np.round(row, 12)) for row in expected}


def test_blocked_by_a_triangle_between_point_and_light():
    roof = np.array(
        [
            [[-1.0, 1.0, -1.0], [1.0, 1.0, -1.0], [0.0, 1.0, 2.0]],
            [[50.0, 0.0, 50.0], [51.0, 0.0, 50.0], [50.0, 0.0, 51.0]],  # far away, "own" face
        ]
    )
    origins = np.array([[0.0, 0.0, 0.0], [5.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    up = np.tile([0.0, 1.0, 0.0], (3, 1))
    hit = report_surface.blocked(origins, up, np.full(3, np.inf), roof, np.ones(3, dtype=int))
    assert hit.tolist() == [True, False, False]
    # The ray stops at a point light below the roof; and a face never blocks itself.
    short = report_surface.blocked(origins, up, np.full(3, 0.5), roof, np.ones(3, dtype=int))
    assert not short.any()
    assert not report_surface.blocked(origins, up, np.full(3, np.inf), roof, np.zeros(3, int)).any()


def test_replace_section_keeps_the_others():
    title = report_surface.TITLE
    document = f"# R\n\n## A\n\na\n\n{title}\n\nold\n\n## B\n\nb\n"
    new = f"{title}\n\nnew\n"
    out = report_surface.replace_section(document, new)
    assert out == f"# R\n\n## A\n\na\n\n{title}\n\nnew\n\n## B\n\nb\n"
    assert report_surface.replace_section("# R\n", new) == f"# R\n\n{new}"
    assert report_surface.existing_section(document) == f"{title}\n\nold\n"
    assert report_surface.existing_section("# R\n\n## A\n") is None


def test_quick_run_writes_the_section(tmp_path):
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        absent("matplotlib is not installed (pip install '.[bench]')")
    output = tmp_path / "REPORT.md"
    output.write_text(f"# R\n\n{report_surface.TITLE}\n\nstale\n\n## Later\n\nkept\n")
    report_surface.main(["--quick", "--output", str(output)])
    text = output.read_text()
    assert text.count(report_surface.TITLE) == 1
    assert "stale" not in text and "## Later\n\nkept" in text
    assert "| sun | shadowgeo shadow_on_surface | exact |" in text
    assert "| point light | shadow map | 128 x 128 |" in text
    assert "### How the cost grows" in text
    assert (tmp_path / "report" / "surface.png").stat().st_size > 0


def test_the_full_report_keeps_the_sections_other_benchmarks_wrote():
    import report

    written = "# Report\n\nintro\n\n## Headline\n\nnew\n\n## Stability\n\nnew too\n"
    existing = (
        "# Report\n\nold intro\n\n## Headline\n\nold\n\n## Scenes at scale\n\nscale table\n\n"
        "## Shadows on every surface\n\nsurface table\n"
    )
    merged = report.keep_other_sections(written, existing)
    assert merged.count("## Headline") == 1 and "\nold\n" not in merged
    assert merged.index("## Stability") < merged.index("## Scenes at scale\n\nscale table")
    assert merged.rstrip().endswith("## Shadows on every surface\n\nsurface table")
