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
