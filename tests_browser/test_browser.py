"""Real-browser tests (``make browser-test``; not collected by ``make test``).

(a) JupyterLab from ``.venv`` on 127.0.0.1 with a token: open a copy of the Thesis I notebook, run all
    cells, move the explorer's stepover slider with the keyboard, check that the readout and the figure
    change. (b) The offline site: load ``build/site/index.html`` (built first from whatever ``build/``
    holds; if no notebook was executed yet, one notebook is run in fast mode), follow a notebook link
    and a figure link, and check in Chromium's performance (network) log that every request stays on
    this machine. Screenshots go to ``build/screens/``.

Needs Debian's ``chromium`` and ``chromium-driver`` (``make browser-test`` installs them) and selenium.
Headless, ``--no-sandbox`` (CI runs as root); every wait has a timeout; the Jupyter server is stopped
(terminate, then kill, by its process id) whatever happens.
"""
from __future__ import annotations

import json
import os
import secrets
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import urlparse

import pytest

os.environ.setdefault("SE_OFFLINE", "true")          # selenium: never look for drivers online
os.environ.setdefault("SE_AVOID_STATS", "true")

from selenium import webdriver  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402
from selenium.webdriver.support.ui import WebDriverWait  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
BUILD = Path(os.environ.get("CNCLAB_BROWSER_BUILD") or (REPO / "build")).resolve()
SCREENS = BUILD / "screens"
NOTEBOOK = REPO / "notebooks" / "jacso2021" / "thesis1_engagement_formulas.ipynb"
#: Run (fast mode) to build a site when nothing was executed yet: an explorer and the 3D views.
SITE_NOTEBOOKS = (NOTEBOOK, REPO / "notebooks" / "mgherony2024" / "ch7_spindle_speed_control.ipynb")
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMEDRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
LOCAL_SCHEMES = {"file", "data", "blob", "about", "chrome", "chrome-extension", "devtools"}
LOCAL_HOSTS = {"127.0.0.1", "localhost", "::1", "[::1]"}

pytestmark = pytest.mark.skipif(not (Path(CHROMIUM).exists() and Path(CHROMEDRIVER).exists()),
                                reason="chromium / chromedriver not installed (make browser-test installs them)")


@pytest.fixture
def driver():
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for a in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
              "--window-size=1400,1000", "--no-first-run", "--disable-background-networking",
              "--disable-component-update", "--disable-sync", "--disable-default-apps",
              "--allow-file-access-from-files"):
        opts.add_argument(a)
    opts.set_capability("goog:loggingPrefs", {"performance": "ALL", "browser": "ALL"})
    d = webdriver.Chrome(options=opts, service=Service(CHROMEDRIVER))
    d.set_page_load_timeout(120)
    d.set_script_timeout(60)
    SCREENS.mkdir(parents=True, exist_ok=True)
    try:
        yield d
    finally:
        d.quit()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def jupyter(tmp_path):
    """JupyterLab from .venv serving a scratch folder (a copy of the notebook: nothing in the repo is
    autosaved), with a random token; yields (base url, token, notebook name)."""
    root = tmp_path / "lab"
    root.mkdir()
    shutil.copy(NOTEBOOK, root / NOTEBOOK.name)
    port, token = _free_port(), secrets.token_hex(16)
    env = dict(os.environ, CNCLAB_FAST="1", CNCLAB_BUILD_DIR=str(tmp_path / "build"), MPLBACKEND="Agg",
               JUPYTER_CONFIG_DIR=str(tmp_path / "jupyter_config"), JUPYTER_RUNTIME_DIR=str(tmp_path / "runtime"))
    settings = tmp_path / "lab_settings" / "@jupyterlab" / "apputils-extension"
    settings.mkdir(parents=True)                      # no "official Jupyter news?" toast, no news fetch
    (settings / "notification.jupyterlab-settings").write_text('{"fetchNews": "false"}')
    env["JUPYTERLAB_SETTINGS_DIR"] = str(tmp_path / "lab_settings")
    jupyter_bin = Path(sys.executable).with_name("jupyter")
    log = open(tmp_path / "jupyter.log", "w")
    proc = subprocess.Popen(
        [str(jupyter_bin), "lab", "--no-browser", "--allow-root", "--ServerApp.ip=127.0.0.1",
         f"--ServerApp.port={port}", "--ServerApp.port_retries=0", f"--IdentityProvider.token={token}",
         f"--ServerApp.root_dir={root}", "--LabApp.expose_app_in_browser=True",
         "--LabApp.news_url=", "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate"],
        cwd=root, env=env, stdout=log, stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            if proc.poll() is not None:
                raise RuntimeError(f"jupyter lab exited: {(tmp_path / 'jupyter.log').read_text()[-2000:]}")
            try:
                with socket.create_connection(("127.0.0.1", port), timeout=1):
                    break
            except OSError:
                time.sleep(0.5)
        else:
            raise RuntimeError("jupyter lab did not start within 120 s")
        yield base, token, NOTEBOOK.name
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=10)
        log.close()


def _wait(driver, cond, timeout, what):
    return WebDriverWait(driver, timeout, poll_frequency=0.5).until(lambda d: cond(d), message=what)


def _state(driver):
    return driver.execute_script(
        "var e = document.querySelector('.cnclab-explorer'); if (!e) return null;"
        "var img = e.querySelector('img'); var ro = e.querySelectorAll('.widget-html-content');"
        "return {img: img ? img.src.length + ':' + img.src.slice(-64) : '',"
        "        text: Array.from(ro).map(function (x) { return x.textContent; }).join(' | ')};")


def test_jupyterlab_explorer_slider_moves_output(driver, jupyter):
    base, token, name = jupyter
    driver.get(f"{base}/lab/tree/{name}?token={token}")
    ready = ("var a = window.jupyterapp; var w = a && a.shell.currentWidget;"
             "return !!(w && w.sessionContext && w.sessionContext.session && w.sessionContext.session.kernel"
             " && w.sessionContext.session.kernel.status === 'idle');")
    _wait(driver, lambda d: d.execute_script(ready), 180, "notebook and kernel ready")
    driver.execute_script("window.jupyterapp.commands.execute('notebook:run-all-cells');")
    _wait(driver, lambda d: len((_state(d) or {}).get("img", "")) > 10, 300, "explorer rendered")
    handle = _wait(driver, lambda d: d.find_element(By.CSS_SELECTOR, ".cnclab-explorer .noUi-handle"), 60,
                   "slider handle")
    driver.execute_script("arguments[0].scrollIntoView({block: 'start'});",
                          driver.find_element(By.CSS_SELECTOR, ".cnclab-explorer"))
    time.sleep(1.0)
    before = _state(driver)
    driver.save_screenshot(str(SCREENS / "jupyterlab_explorer_before.png"))
    value0 = handle.get_attribute("aria-valuenow") or handle.get_attribute("aria-valuetext")
    handle.click()                                   # focus the stepover slider's handle
    for _ in range(8):                               # keyboard: 8 steps of 0.1 mm to the right
        handle.send_keys(Keys.ARROW_RIGHT)
        time.sleep(0.1)
    _wait(driver, lambda d: _state(d) != before, 60, "explorer output changed after the slider moved")
    value1 = handle.get_attribute("aria-valuenow") or handle.get_attribute("aria-valuetext")
    # let the kernel work through every key press: the readout's Thesis I stepover s(theta(s), rho)
    # must then equal the slider's value (the explorer drew the final state, not an intermediate one)
    _wait(driver, lambda d: f"s(θ, ρ) = {float(value1):.4f} mm" in (_state(d) or {}).get("text", ""), 120,
          f"readout for the final slider value {value1}")
    _wait(driver, lambda d: d.execute_script(ready), 60, "kernel idle")
    time.sleep(1.0)
    after = _state(driver)
    driver.save_screenshot(str(SCREENS / "jupyterlab_explorer_after.png"))
    assert value1 != value0, (value0, value1)
    assert after["img"] != before["img"] and after["text"] != before["text"]


def _ensure_site() -> Path:
    index = BUILD / "site" / "index.html"
    if index.is_file():
        return index
    env = dict(os.environ, CNCLAB_BUILD_DIR=str(BUILD), CNCLAB_FAST="1", MPLBACKEND="Agg")
    if not list((BUILD / "notebooks").rglob("*.ipynb")):    # nothing executed yet: two notebooks, fast mode
        for nb_path in SITE_NOTEBOOKS:
            code = ("import nbformat; from pathlib import Path; from cnclab.reproduce import execute_notebook;"
                    f"from cnclab.paths import build_dir; p = Path({str(nb_path)!r});"
                    "nb = execute_notebook(p, timeout=900);"
                    "d = build_dir() / 'notebooks' / p.parent.name / p.name; d.parent.mkdir(parents=True, exist_ok=True);"
                    "nbformat.write(nb, d)")
            subprocess.run([sys.executable, "-c", code], env=env, check=True, timeout=1200, cwd=REPO)
    subprocess.run([sys.executable, "-m", "cnclab", "site"], env=env, check=True, timeout=1200, cwd=REPO)
    return index


def _requests(driver) -> list[str]:
    urls = []
    for entry in driver.get_log("performance"):
        msg = json.loads(entry["message"])["message"]
        if msg.get("method") in ("Network.requestWillBeSent", "Network.webSocketCreated"):
            urls.append(msg["params"].get("request", {}).get("url") or msg["params"].get("url", ""))
    return urls


def _leaves_machine(url: str) -> bool:
    u = urlparse(url)
    if u.scheme in LOCAL_SCHEMES:
        return False
    return (u.hostname or "") not in LOCAL_HOSTS


def test_offline_site_loads_follows_links_and_stays_local(driver):
    index = _ensure_site()
    driver.get(index.as_uri())
    _wait(driver, lambda d: d.find_elements(By.ID, "works"), 60, "site front page")
    driver.save_screenshot(str(SCREENS / "site_front_page.png"))
    assert "Jacsó" in driver.page_source and "Mgherony" in driver.page_source
    nb_links = [a.get_attribute("href") for a in driver.find_elements(By.CSS_SELECTOR, "#notebooks + ul a")]
    fig_links = [a.get_attribute("href") for a in driver.find_elements(By.CSS_SELECTOR, ".gallery a")
                 if a.get_attribute("href").endswith((".png", ".svg"))]
    assert nb_links, "the site lists no executed notebook"
    assert fig_links, "the site's gallery has no figure"
    seen = _requests(driver)
    driver.get(nb_links[0])
    _wait(driver, lambda d: d.find_elements(By.CSS_SELECTOR, ".jp-Notebook, .jp-Cell"), 120, "notebook page")
    time.sleep(2.0)
    driver.save_screenshot(str(SCREENS / "site_notebook.png"))
    seen += _requests(driver)
    driver.get(index.as_uri())
    driver.get(fig_links[0])
    time.sleep(1.0)
    driver.save_screenshot(str(SCREENS / "site_figure.png"))
    seen += _requests(driver)
    driver.get(index.as_uri())
    views = [a.get_attribute("href") for a in driver.find_elements(By.CSS_SELECTOR, ".gallery a")
             if a.get_attribute("href").endswith(".html")]
    if views:                                        # a 3D view page (plotly.js inlined) renders offline
        driver.get(views[0])
        _wait(driver, lambda d: d.find_elements(By.CSS_SELECTOR, ".js-plotly-plot .main-svg, .js-plotly-plot canvas"),
              120, "3D view rendered")
        time.sleep(2.0)
        driver.save_screenshot(str(SCREENS / "site_3d_view.png"))
        seen += _requests(driver)
    assert any(u.startswith("file://") for u in seen)
    outside = sorted({u for u in seen if _leaves_machine(u)})
    assert not outside, f"requests leaving the machine: {outside[:10]}"
