"""End-to-end in a real browser: Debian's headless chromium driven by Selenium through chromium-driver.

Creates a subject, runs two virtual-rig sessions through the whole camera path (MediaPipe segmentation,
registration), the second with a swollen left forearm (``bsv.bodies`` local modifier
``arms/l-lowerarm-fat``), opens the comparison page and checks that forearm_l, and only it, is flagged.
Screenshots of every page go to tests/artifacts/station/ (git-ignored)."""

from __future__ import annotations

import shutil
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("fastapi", reason="BSV Station needs requirements-station.txt (scripts/setup.sh installs it)")
pytest.importorskip("selenium", reason="selenium is in requirements-station.txt")

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import Select, WebDriverWait
from station_server import ARTIFACTS, Server

DRIVER = "/usr/bin/chromedriver"
pytestmark = pytest.mark.skipif(shutil.which("chromium") is None or not Path(DRIVER).exists(),
                                reason="needs Debian's chromium and chromium-driver (apt-get install chromium "
                                       "chromium-driver; scripts/setup.sh does it as root)")


@pytest.fixture
def browser() -> Iterator[Any]:
    opts = webdriver.ChromeOptions()
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--window-size=1400,1100"):
        opts.add_argument(arg)
    drv = webdriver.Chrome(service=Service(DRIVER), options=opts)
    drv.implicitly_wait(20)  # find_element waits for the next page after a click
    try:
        yield drv
    finally:
        drv.quit()


def _shot(drv: Any, name: str) -> None:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    drv.save_screenshot(str(ARTIFACTS / f"{name}.png"))


def _capture(drv: Any, swollen: str | None, shot: str, timeout: float = 300.0, button: str = "capture") -> float:
    if swollen is not None:
        WebDriverWait(drv, 30).until(lambda d: d.find_elements(By.ID, "swollen"))  # the subject page has loaded
        Select(drv.find_element(By.ID, "swollen")).select_by_value(swollen)
    t0 = time.monotonic()
    before = drv.current_url
    drv.find_element(By.ID, button).click()
    WebDriverWait(drv, 20).until(lambda d: d.current_url != before and "/jobs/" in d.current_url)
    assert drv.find_element(By.ID, "job").get_attribute("data-kind") == "capture"
    WebDriverWait(drv, timeout, poll_frequency=1).until(
        lambda d: d.find_element(By.ID, "state").text in ("done", "failed"))
    elapsed = time.monotonic() - t0
    _shot(drv, shot)
    assert drv.find_element(By.ID, "state").text == "done", drv.find_element(By.ID, "message").text
    drv.find_element(By.ID, "subject-link").click()
    return elapsed


@pytest.mark.slow
def test_two_virtual_sessions_and_the_comparison_flag_the_swollen_forearm(browser: Any, tmp_path: Path) -> None:
    server = Server(tmp_path / "data").start()
    try:
        drv = browser
        drv.get(server.url + "/")
        _shot(drv, "01-home")
        drv.find_element(By.ID, "code").send_keys("LYM-0001")
        Select(drv.find_element(By.ID, "sex")).select_by_value("female")
        drv.find_element(By.ID, "birth_year").send_keys("1971")
        drv.find_element(By.ID, "height_m").send_keys("1.63")
        drv.find_element(By.ID, "mass_kg").send_keys("64")
        drv.find_element(By.ID, "create").click()
        assert drv.find_element(By.ID, "subject-code").text == "LYM-0001"
        assert "LYM" not in drv.current_url
        _shot(drv, "02-subject-new")
        # preview and pose check before the capture: the job page reloads with both images and the check
        drv.find_element(By.ID, "preview").click()
        WebDriverWait(drv, 300, poll_frequency=1).until(lambda d: d.find_elements(By.ID, "a-pose"))
        assert drv.find_element(By.ID, "a-pose").text == "A-pose"
        _shot(drv, "03-preview-pose-check")
        first = _capture(drv, None, "03-job-baseline", button="capture-now")
        second = _capture(drv, "forearm_l", "04-job-swollen")
        print(f"\nvirtual-rig session (MediaPipe camera path) seen from the browser: {first:.1f} s, {second:.1f} s")
        assert drv.find_element(By.ID, "history-chart").is_displayed()
        _shot(drv, "05-subject-history")
        drv.find_element(By.ID, "compare").click()
        WebDriverWait(drv, 30).until(lambda d: d.find_elements(By.CSS_SELECTOR, "#changes tbody tr[data-segment]"))
        rows = drv.find_elements(By.CSS_SELECTOR, "#changes tbody tr[data-segment]")
        flags = {r.get_attribute("data-segment"): r.get_attribute("data-significant") for r in rows}
        _shot(drv, "06-compare")
        assert flags["forearm_l"] == "yes", flags
        # Nothing the swelling left unchanged may be flagged. What it changed, besides the forearm: the
        # upper arm near the elbow (+1.1 %) and the aggregates holding it (trunk_limbs +0.5 %, which the
        # camera-path interval of about +-0.45 % can resolve).
        from bsv.station.rig import virtual_body

        truth = [virtual_body(0, 0, swollen)[1] for swollen in (None, "forearm_l")]
        changed = {k for k in truth[0] if abs(truth[1][k] / truth[0][k] - 1.0) > 1e-3}
        flagged = {s for s, f in flags.items() if f == "yes"}
        assert flagged <= changed, (flags, sorted(changed))
        assert "intervals from the pipeline" in drv.find_element(By.ID, "interval-source").text
        drv.get(server.url + "/sessions/2")
        _shot(drv, "07-session")
        drv.get(server.url + "/rig")
        _shot(drv, "08-rig")
        assert drv.find_element(By.ID, "cameras").text
    finally:
        server.stop()
    assert "LYM-0001" not in server.log.read_text()  # no subject code in the server's log
