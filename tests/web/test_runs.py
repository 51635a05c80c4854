"""The run pages and commands against a stand-in supervisor (tests/web/_fake_supervisor.py)."""

from __future__ import annotations

import html

RUN = "20261129T120000Z-abcdef"


def _plan_text():
    from imucalib.plan.io import plan_to_toml
    from imucalib.procedures.p1.plan import generate_p1_plan

    return plan_to_toml(generate_p1_plan())


def test_an_invalid_plan_is_shown_per_step_and_field(browser, supervisor):
    operator = browser("operator")
    operator.post("/lock/take")
    text = _plan_text().replace("rate_dps = ", "rate_dps = \"fast\" #", 1)
    answer = operator.post("/runs/new", {"station": "sim", "serials": "SN1"},
                           files={"plan_upload": ("bad.toml", text.encode(), "text/plain")})
    assert answer.status_code == 422
    page = html.unescape(answer.text)
    assert "The run was not started" in page
    row = page.split('id="errors"')[1]
    assert "rate_dps" in row and "fast" in row
    assert [c for c in supervisor.calls if c[0] == "start"] == []


def test_form_errors_name_the_field(browser, web_app, supervisor):
    operator = browser("operator")
    operator.post("/lock/take")
    (web_app.state.web.plans_dir / "p1.toml").write_text(_plan_text(), encoding="utf-8")
    page = operator.get("/runs/new")
    assert '<option value="p1.toml"' in page.text
    answer = operator.post("/runs/new", {"plan_file": "p1.toml", "station": "sim",
                                         "serials": "SN 1;;bad serial!"})
    assert answer.status_code == 422
    assert "a serial is letters, digits" in html.unescape(answer.text)
    neither = operator.post("/runs/new", {"station": "sim", "serials": "SN1"})
    assert neither.status_code == 422 and "choose a plan" in neither.text
    escape = operator.post("/runs/new", {"plan_file": "../records.db", "station": "sim",
                                         "serials": "SN1"})
    assert escape.status_code == 422 and "one of the listed files" in html.unescape(escape.text)
    started = operator.post("/runs/new", {"plan_file": "p1.toml", "station": "sim",
                                          "serials": "SN1"})
    assert started.status_code == 303


def test_a_stale_command_is_refused(browser, supervisor):
    operator = browser("operator")
    operator.post("/lock/take")
    stale = operator.client.post(f"/runs/{RUN}/answer",
                                 data={"prompt_id": 6, "step_index": 1, "confirmed": "true"},
                                 headers={"X-CSRF-Token": operator.csrf,
                                          "Accept": "application/json"})
    assert stale.status_code == 409 and "not the current one" in stale.json()["error"]
    old_step = operator.post(f"/runs/{RUN}/abort", {"step_index": 0})
    assert old_step.status_code == 409
    ok = operator.client.post(f"/runs/{RUN}/answer",
                              data={"prompt_id": 7, "step_index": 1, "confirmed": "false",
                                    "note": "cube not seated"},
                              headers={"X-CSRF-Token": operator.csrf,
                                       "Accept": "application/json"})
    assert ok.json() == {"ok": True, "run_id": RUN, "done": "answer"}
    assert supervisor.calls[-1] == ("answer", (RUN, 7, 1, False, "Oli Operator",
                                               "cube not seated"))
    again = operator.post(f"/runs/{RUN}/abort", {"step_index": 1})
    assert again.status_code == 409 and "nothing to abort" in again.text


def test_an_unknown_run_is_not_found(browser):
    operator = browser("operator")
    assert operator.get("/runs/20990101T000000Z-000000").status_code == 404
    assert operator.post("/runs/20990101T000000Z-000000/abort").status_code == 404


def test_the_pages_show_the_run(browser):
    observer = browser("observer")
    station = observer.get("/")
    assert f'href="/runs/{RUN}"' in station.text and "waiting" in station.text
    page = observer.get(f"/runs/{RUN}")
    assert "p1-short" in page.text and 'id="run-data"' in page.text
    assert 'id="abort"' not in page.text                 # an observer sees no commands
    assert 'id="abort"' in browser("operator").get(f"/runs/{RUN}").text
    results = observer.get(f"/runs/{RUN}/results").text  # a waiting run: not calibrated yet
    assert "it is calibrated when it finishes" in results and "Files" in results


def test_the_socket_streams_the_run_s_events(browser, supervisor):
    operator = browser("operator")
    operator.post("/lock/take")
    with operator.client.websocket_connect(f"/ws/runs/{RUN}",
                                           headers={"origin": "http://testserver"}) as ws:
        assert ws.receive_json()["type"] == "snapshot"
        operator.post(f"/runs/{RUN}/answer", {"prompt_id": 7, "step_index": 1,
                                              "confirmed": "true"})
        event = ws.receive_json()
        supervisor._publish(RUN, {"type": "end", "run_id": RUN, "status": "finished"})
        assert ws.receive_json()["type"] == "end"
        assert ws.receive()["type"] == "websocket.close"      # the server closes at the end
    assert event == {"type": "prompt_closed", "run_id": RUN, "confirmed": True,
                     "who": "Oli Operator"}
    assert supervisor._queues[RUN] == []


def test_no_supervisor_is_one_line(records_url, tmp_path, monkeypatch, web):
    from fastapi.testclient import TestClient

    from imucalib.web import context
    from imucalib.web.app import create_app

    def unavailable(self):
        raise context.SupervisorUnavailableError("the run supervisor is not available: test")

    monkeypatch.setattr(context.WebContext, "runs", unavailable)
    web.add_users(records_url)
    app = create_app(records_url, tmp_path / "runs")
    try:
        client = TestClient(app)
        web.login(client, "Oli Operator")
        assert "the run supervisor is not available" in client.get("/").text
        assert client.get(f"/runs/{RUN}", follow_redirects=False).status_code == 503
    finally:
        app.state.web.close()
