// The run page: live events over /ws/runs/{id}; commands as POSTs with the CSRF token.
// A lost socket only reconnects: it never acts on the run (docs/web.md, "Live view").
"use strict";
(function () {
  const data = JSON.parse(document.getElementById("run-data").textContent);
  const runId = data.run_id;
  const csrf = document.getElementById("csrf").value;
  const $ = (id) => document.getElementById(id);
  let view = data;
  let prompt = data.prompt;
  const live = new Set(["starting", "running", "waiting", "aborting"]);

  function setStatus(status, error) {
    view.status = status;
    $("status").textContent = status;
    if (error !== undefined) { $("error").textContent = error || ""; }
    const resume = $("resume");
    if (resume) { resume.hidden = live.has(status) || status === "finished"; }
  }
  function setStep(index, state) {
    const li = document.querySelector(`#steps li[data-index="${index}"]`);
    if (!li) { return; }
    li.className = "step-" + state;
    li.querySelector(".state").textContent = state;
    if (state === "running") {
      view.step_index = index;
      $("step").textContent = index + 1;
      $("progress").value = index;
    }
  }
  function showPrompt(p) {
    prompt = p;
    $("prompt-text").textContent = p.text;
    $("prompt-note").value = "";
    const dialog = $("prompt");
    if (!dialog.open) { dialog.showModal(); }
  }
  function closePrompt() {
    prompt = null;
    const dialog = $("prompt");
    if (dialog.open) { dialog.close(); }
  }
  function appendLog(line) {
    const log = $("log");
    log.textContent += line + "\n";
    const lines = log.textContent.split("\n");
    if (lines.length > 500) { log.textContent = lines.slice(-500).join("\n"); }
    log.scrollTop = log.scrollHeight;
  }
  function apply(event) {
    switch (event.type) {
      case "snapshot":
        view = event.view;
        setStatus(view.status, view.error);
        view.steps.forEach((s) => setStep(s.index, s.state));
        $("time-left").textContent = Math.round(view.time_left_s);
        if (view.prompt) { showPrompt(view.prompt); } else { closePrompt(); }
        $("signals").textContent = JSON.stringify(view.signals, null, 1);
        break;
      case "status": setStatus(event.status, event.error); break;
      case "step": setStep(event.index, event.state); break;
      case "prompt": showPrompt(event); break;
      case "prompt_closed": closePrompt(); break;
      case "log": appendLog(event.line); break;
      case "signals":
        $("signals").textContent = JSON.stringify(event.signals, null, 1);
        if (event.time_left_s !== undefined) {
          $("time-left").textContent = Math.round(event.time_left_s);
        }
        break;
      case "safe_stop": appendLog(`safe stop: ${event.device}`); break;
      case "command_rejected": appendLog(`command refused: ${event.reason}`); break;
      case "end": setStatus(event.status); closePrompt(); break;
    }
  }
  async function command(path, fields) {
    const body = new FormData();
    for (const [k, v] of Object.entries(fields)) {
      if (v !== null && v !== undefined) { body.append(k, String(v)); }
    }
    const response = await fetch(`/runs/${encodeURIComponent(runId)}/${path}`, {
      method: "POST", body, credentials: "same-origin",
      headers: { "X-CSRF-Token": csrf, "Accept": "application/json" },
    });
    const answer = await response.json().catch(() => ({ error: response.statusText }));
    if (!response.ok) { appendLog(`${path} refused: ${answer.error}`); }
    return response.ok;
  }
  function answer(confirmed) {
    if (!prompt) { return; }
    command("answer", { prompt_id: prompt.prompt_id, step_index: prompt.step_index,
                        confirmed, note: $("prompt-note").value });
    closePrompt();
  }
  $("confirm").addEventListener("click", () => answer(true));
  $("refuse").addEventListener("click", () => answer(false));
  const abort = $("abort");
  if (abort) {
    abort.addEventListener("click", () => {
      if (window.confirm("Stop the run safely now?")) {
        command("abort", { step_index: view.step_index });
      }
    });
  }
  const resume = $("resume");
  if (resume) { resume.addEventListener("click", () => command("resume", {})); }
  setStatus(view.status);

  let delay = 500;
  function connect() {
    const scheme = location.protocol === "https:" ? "wss:" : "ws:";
    const socket = new WebSocket(`${scheme}//${location.host}/ws/runs/${encodeURIComponent(runId)}`);
    socket.onopen = () => { $("connection").textContent = "live"; delay = 500; };
    socket.onmessage = (message) => apply(JSON.parse(message.data));
    socket.onclose = (closed) => {
      $("connection").textContent = `disconnected (${closed.code})`;
      if (closed.code === 4401) { location.href = "/login?next=" + encodeURIComponent(location.pathname); return; }
      if (closed.code >= 4400 || !live.has(view.status)) { return; }
      setTimeout(connect, delay);
      delay = Math.min(delay * 2, 10000);
    };
  }
  connect();
})();
