"""The HTML report in a real browser: headless Chromium (Debian's ``chromium`` and
``chromium-driver``), driven by Selenium, opens a report built from real bags.

Where Chromium, its driver or Selenium is missing the test skips and says which; ``.ci/run``
installs them and sets ``PIC4RL_REQUIRE_BROWSER=1``, under which a missing one fails instead.
The screenshot stays in the test's temporary folder (pytest keeps the last runs').
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from urllib.parse import unquote, urlparse

import pytest

from pic4rl_metrics.cli import commands as cli

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--window-size=1300,1800")


def _missing() -> str | None:
    for path, package in ((CHROMIUM, "chromium"), (CHROMEDRIVER, "chromium-driver")):
        if not (Path(path).is_file() or shutil.which(Path(path).name)):
            return f"no {path}: apt-get install chromium chromium-driver"
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "selenium is not installed: pip install '.[test]'"
    return None


@pytest.fixture
def browser(tmp_path: Path):
    why = _missing()
    if why is not None:
        if os.environ.get("PIC4RL_REQUIRE_BROWSER"):
            pytest.fail(f"PIC4RL_REQUIRE_BROWSER is set but {why}")
        pytest.skip(why)
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium") or CHROMIUM
    for flag in (*FLAGS, f"--user-data-dir={tmp_path / 'profile'}"):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(shutil.which("chromedriver") or CHROMEDRIVER),
                              options=options)
    try:
        yield driver
    finally:
        driver.quit()


def _column(driver, table: str, col: int) -> list[str]:
    return driver.execute_script(
        "return Array.from(document.getElementById(arguments[0]).tBodies[0].rows)"
        ".map(r => r.cells[arguments[1]].textContent.trim())", table, col)


def test_the_report_works_in_chromium(browser, bench_bags: Path, tmp_path: Path) -> None:
    out = tmp_path / "report.html"
    assert cli.main(["report", str(bench_bags), "--out", str(out), "--reference", "dwa"]) == 0
    browser.get(out.as_uri())
    assert browser.execute_script("return document.readyState") == "complete"

    images = browser.execute_script(
        "return Array.from(document.images).map(i => [i.complete, i.naturalWidth])")
    assert images and all(done and width > 0 for done, width in images), images

    header = browser.find_elements("css selector", "#episodes thead th")
    names = [h.text for h in header]
    time_col, agent_col = names.index("time [s]"), names.index("agent")
    before = _column(browser, "episodes", time_col)
    header[time_col].click()
    ascending = _column(browser, "episodes", time_col)
    numbers = [float(v) for v in ascending if v != "–"]
    assert numbers == sorted(numbers) and ascending != before
    header[time_col].click()
    descending = [float(v) for v in _column(browser, "episodes", time_col) if v != "–"]
    assert descending == sorted(numbers, reverse=True)

    box = browser.find_element("css selector", 'input.filter[data-table="episodes"]')
    box.send_keys("planner collision")
    shown = browser.execute_script(
        "return Array.from(document.getElementById('episodes').tBodies[0].rows)"
        ".filter(r => !r.hidden).map(r => r.textContent)")
    agents = _column(browser, "episodes", agent_col)
    assert len(shown) < len(agents)
    assert all("planner" in row and "collision" in row for row in shown)
    count = browser.find_element("id", "episodes-count").text
    assert count == f"{len(shown)} of {len(agents)} rows"

    links = [a.get_attribute("href") for a in browser.find_elements("css selector", "a.bag")]
    assert links and all(Path(unquote(urlparse(h).path)).is_dir() for h in links)

    shot = tmp_path / "report.png"
    browser.execute_script("window.scrollTo(0, 0)")
    assert browser.save_screenshot(str(shot)) and shot.stat().st_size > 10_000
    errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    assert errors == []


def test_the_report_fits_a_laptops_width(browser, tmp_path: Path) -> None:
    """At a 1280 px window (issue 37, item 12): long agent names, a reference, a bag whose
    error names a long path; no table is wider than its container, no cell's content spills
    out of it, the page does not scroll sideways and the paired table's verdict is in view.
    Each figure's save link holds its image; the leaderboard's downloads are data: URIs."""
    from pic4rl_metrics.synthetic.synthetic_bench import write_benchmark

    bags = tmp_path / "bags"
    write_benchmark(bags, {"sac_lidar_explorer_dagger_v2": 0.8, "td3_depth_explorer_memory": 0.5,
                           "planner_with_margin": 0.95}, pairs=4, runs=2)
    bad = bags / "run0" / ("a_bag_folder_whose_name_is_long_and_has_no_space_to_break_a_line_at_"
                           "anywhere_in_it")
    bad.mkdir()
    (bad / "metadata.yaml").write_text("rosbag2_bagfile_information: [")
    out = tmp_path / "report.html"
    assert cli.main(["report", str(bags), "--out", str(out), "--reference",
                     "planner_with_margin", "--no-progress"]) == 1
    browser.set_window_size(1280, 1000)
    browser.get(out.as_uri())
    inner, client, scroll = browser.execute_script(
        "const d = document.documentElement;"
        "return [window.innerWidth, d.clientWidth, d.scrollWidth]")
    assert inner <= 1280 and scroll <= client, (inner, client, scroll)
    tables = browser.execute_script(
        "return Array.from(document.querySelectorAll('table')).map(t => {"
        "  const box = t.parentElement, r = t.getBoundingClientRect();"
        "  return [t.id, r.right, box.getBoundingClientRect().right, box.scrollWidth,"
        "          box.clientWidth]; })")
    ids = {t[0].split("-")[0] for t in tables}  # a table per task and world set: paired-2, ...
    assert ids >= {"leaderboard", "paired", "episodes", "errors", "inputs"}
    for name, right, box_right, box_scroll, box_client in tables:
        assert right <= box_right + 0.5 and box_scroll <= box_client, (name, right, box_right)
    spills = browser.execute_script(
        "return Array.from(document.querySelectorAll('td, th'))"
        ".filter(c => c.offsetParent !== null && c.scrollWidth > c.clientWidth + 1)"
        ".map(c => c.textContent.slice(0, 40))")
    assert spills == []
    verdict = browser.execute_script(
        "const th = document.querySelector('table[id^=paired] thead th:last-child');"
        "const r = th.getBoundingClientRect(); return [th.textContent, r.left, r.right]")
    assert verdict[0] == "verdict" and 0 <= verdict[1] < verdict[2] <= inner
    saves = browser.execute_script(
        "return Array.from(document.querySelectorAll('figure')).map(f =>"
        " [f.querySelector('a.save').href === f.querySelector('img').src,"
        "  f.querySelector('a.save').download])")
    assert saves and all(same and name.endswith(".png") for same, name in saves)
    exports = browser.execute_script(
        "return Array.from(document.querySelectorAll('a.export')).map(a => a.href)")
    assert [e.partition(",")[0] for e in exports] == [
        "data:text/csv;charset=utf-8", "data:application/x-tex;charset=utf-8"]
