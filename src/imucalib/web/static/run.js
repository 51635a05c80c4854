// The run page: live events over /ws/runs/{id}; commands as POSTs with the CSRF token.
// A lost socket only reconnects: it never acts on the run. Every command carries what the page
// showed (the run id in its path, the step, the prompt), so a stale page is refused (409)
// rather than acting on a state its operator did not see (docs/web.md, "Live view").
"use strict";
(function () {
  const data = JSON.parse(document.getElementById("run-data").textContent);
  const runId = data.run_id;
  const csrf = document.getElementById("csrf").value;
  const $ = (id) => document.getElementById(id);
  const live = new Set(["starting", "running", "waiting", "aborting"]);
  //: Live samples kept per unit for its traces (5 a second: two minutes).
  const MAX_SAMPLES = 600;
  //: Temperature points kept for the soak chart (thinned by two beyond).
  const MAX_TRACE = 1200;
  let view = data;
  let prompt = data.prompt;
  let samples = {};        // unit -> [{t, gyro, accel}]
  let trace = [];          // [{time_s, air_degc, setpoint_degc, unit_degc}]
  let windows = [];        // window events, in order
  let soak = null;         // the running soak's criterion, from the latest signals

  // --- formatting ---------------------------------------------------------------------------
  function num(v, digits) {
    return (v === null || v === undefined || !Number.isFinite(v)) ? "–" : v.toFixed(digits);
  }
  function vec(values, digits) {
    return Array.isArray(values) && values.length ? values.map((v) => num(v, digits)).join(", ") : "–";
  }
  function duration(s) {
    if (!Number.isFinite(s)) { return "–"; }
    s = Math.max(0, Math.round(s));
    const h = Math.floor(s / 3600), m = Math.floor((s % 3600) / 60), r = s % 60;
    return h ? `${h} h ${String(m).padStart(2, "0")} min` : m ? `${m} min ${String(r).padStart(2, "0")} s` : `${r} s`;
  }

  // --- status, steps, prompt, log -----------------------------------------------------------
  function setStatus(status, error) {
    view.status = status;
    $("status").textContent = status;
    if (status === "finished") { $("time-left").textContent = duration(0); }
    if (error !== undefined) { $("error").textContent = error || ""; }
    const resume = $("resume");
    if (resume) { resume.hidden = live.has(status) || status === "finished"; }
    const abort = $("abort");
    if (abort) { abort.disabled = !live.has(status) || status === "aborting"; }
  }
  function countDone() {
    const done = document.querySelectorAll("#steps li.step-done").length;
    $("done-count").textContent = done;
    $("progress").value = done;
  }
  function setStep(index, state) {
    const li = document.querySelector(`#steps li[data-index="${index}"]`);
    if (!li) { return; }
    li.className = "step-" + state;
    li.querySelector(".state").textContent = state;
    if (state === "running") {
      view.step_index = index;
      $("step").textContent = index + 1;
      li.scrollIntoView({ block: "nearest" });
    }
    countDone();
  }
  function showPrompt(p) {
    prompt = p;
    $("prompt-text").textContent = p.text;
    const d = p.details || {};
    const parts = [];
    if (d.remount) { parts.push(`remount: ${d.remount} up, yaw ${d.remount_yaw_deg || 0}°`); }
    if (d.swap_units) { parts.push(`swap ${d.swap_units.join(" and ")}`); }
    if (d.centrifuge_load_kg !== undefined) { parts.push(`load ${d.centrifuge_load_kg} kg`); }
    $("prompt-details").textContent = parts.join(" · ");
    window.RemountFigure.draw($("prompt-figure"), d.remount || null,
                              Number(d.remount_yaw_deg || 0));
    if ($("prompt-note")) { $("prompt-note").value = ""; }
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

  // --- live values --------------------------------------------------------------------------
  function showSignals(sig, timeLeft) {
    if (!sig) { return; }
    if (Number.isFinite(timeLeft)) { $("time-left").textContent = duration(timeLeft); }
    $("station-time").textContent = Number.isFinite(sig.time_s) ? `station time ${num(sig.time_s, 1)} s` : "";
    const table = sig.table || {}, fuge = sig.centrifuge || {}, ch = sig.chamber || {};
    $("v-table-angle").textContent = vec(table.angle_deg, 3);
    $("v-table-rate").textContent = vec(table.rate_dps, 3);
    $("v-fuge-rate").textContent = vec(fuge.rate_dps, 2);
    $("v-setpoint").textContent = num(ch.setpoint_degc, 2);
    $("v-air").textContent = num(ch.air_degc, 2);
    const unitT = ch.unit_degc || {};
    $("v-units").textContent = Object.keys(unitT).length
      ? Object.entries(unitT).map(([k, v]) => `${k} ${num(v, 2)}`).join(" · ") : "–";
    const g = sig.guards || {};
    const faults = Object.entries(g.faults || {}).filter(([, v]) => v);
    $("guards").textContent = `trips ${g.trips || 0}` +
      (g.last_event ? ` · last: ${g.last_event}` : "") +
      (faults.length ? ` · faults: ${faults.map(([k, v]) => `${k}: ${v}`).join("; ")}` : " · no faults");
    $("guards").className = faults.length || g.trips ? "error" : "muted";
    soak = sig.soak || null;
    const t = sig.time_s;
    if (Number.isFinite(t)) {
      for (const [name, u] of Object.entries(sig.imus || {})) {
        const list = samples[name] || (samples[name] = []);
        if (!list.length || list[list.length - 1].t < t) {
          list.push({ t, gyro: u.gyro_dps || [], accel: u.accel_g || [], temp: u.temperature_degc });
          if (list.length > MAX_SAMPLES) { list.splice(0, list.length - MAX_SAMPLES); }
        }
      }
      if (ch.air_degc !== undefined || Object.keys(unitT).length) {
        addTrace({ time_s: t, air_degc: ch.air_degc, setpoint_degc: ch.setpoint_degc, unit_degc: unitT });
      }
    }
    drawUnits();
    drawSoak();
  }
  function addTrace(point) {
    const last = trace[trace.length - 1];
    if (last && point.time_s <= last.time_s) { return; }
    trace.push(point);
    if (trace.length > MAX_TRACE) { trace = trace.filter((_p, i) => i % 2 === 0); }
  }

  // --- charts -------------------------------------------------------------------------------
  const AXES = ["x", "y", "z"];
  function unitBox(name) {
    const id = "unit-" + name.replace(/[^A-Za-z0-9_-]/g, "_");
    let box = document.getElementById(id);
    if (!box) {
      box = document.createElement("div");
      box.id = id;
      box.className = "unit";
      const h = document.createElement("h3");
      h.textContent = name;
      const values = document.createElement("p");
      values.className = "unit-values";
      box.append(h, values);
      for (const kind of ["gyro", "accel"]) {
        const svg = document.createElementNS("http://www.w3.org/2000/svg", "svg");
        svg.setAttribute("viewBox", "0 0 640 160");
        svg.setAttribute("class", "chart " + kind);
        box.appendChild(svg);
      }
      $("units").appendChild(box);
    }
    return box;
  }
  function drawUnits() {
    for (const [name, list] of Object.entries(samples)) {
      if (!list.length) { continue; }
      const box = unitBox(name);
      const last = list[list.length - 1];
      box.querySelector(".unit-values").textContent =
        `gyro ${vec(last.gyro, 4)} °/s · accel ${vec(last.accel, 4)} g · ${num(last.temp, 2)} °C`;
      const svgs = box.querySelectorAll("svg");
      [["gyro", "°/s"], ["accel", "g"]].forEach(([kind, unit], k) => {
        LiveChart.draw(svgs[k], {
          series: AXES.map((_a, i) => ({ cls: "s" + i,
            points: list.map((s) => [s.t, s[kind][i] === null ? NaN : s[kind][i]]) })),
          legend: AXES.map((a, i) => ({ cls: "s" + i, label: `${kind} ${a}` })),
          xLabel: "station time [s]", yLabel: `[${unit}]` });
      });
    }
  }
  function drawSoak() {
    const names = new Set();
    trace.forEach((p) => Object.keys(p.unit_degc || {}).forEach((n) => names.add(n)));
    const series = [
      { cls: "s0", points: trace.filter((p) => p.air_degc !== null && p.air_degc !== undefined)
        .map((p) => [p.time_s / 60, p.air_degc]) },
      { cls: "s3", dashed: true, points: trace.filter((p) => p.setpoint_degc !== null && p.setpoint_degc !== undefined)
        .map((p) => [p.time_s / 60, p.setpoint_degc]) },
    ];
    [...names].forEach((n, i) => series.push({ cls: "s" + (4 + i % 3),
      points: trace.filter((p) => p.unit_degc && p.unit_degc[n] !== null && p.unit_degc[n] !== undefined)
        .map((p) => [p.time_s / 60, p.unit_degc[n]]) }));
    const legend = [{ cls: "s0", label: "air" }, { cls: "s3", label: "set point" }];
    [...names].forEach((n, i) => legend.push({ cls: "s" + (4 + i % 3), label: n }));
    let band = null;
    const c = $("soak-criterion");
    if (soak) {
      band = { y0: soak.setpoint_degc - soak.band_degc, y1: soak.setpoint_degc + soak.band_degc };
      const spans = Object.entries(soak.unit_span_degc || {})
        .map(([k, v]) => `${k} ${num(v, 3)} °C`).join(", ");
      c.textContent = `Soak at ${soak.setpoint_degc} °C: air within ±${soak.band_degc} °C for ` +
        `${duration(soak.in_band_s)} of the ${duration(soak.stable_for_s)} needed; each unit may vary ` +
        `at most ${soak.imu_band_degc} °C over that time (now: ${spans || "–"}); time-out ${duration(soak.timeout_s)}.`;
      c.className = soak.in_band_s >= soak.stable_for_s ? "ok" : "";
    } else {
      c.textContent = "No soak step running.";
      c.className = "muted";
    }
    LiveChart.draw($("soak-chart"), { series, band, legend, xLabel: "station time [min]", yLabel: "[°C]" });
  }
  function addWindow(w) {
    if (windows.some((x) => x.step_index === w.step_index && x.t_start_s === w.t_start_s)) { return; }
    windows.push(w);
    const body = document.querySelector("#window-table tbody");
    for (const [name, u] of Object.entries(w.units || {})) {
      const tr = document.createElement("tr");
      const pm = (m, e, d) => (m || []).map((v, i) => `${num(v, d)} ± ${num((e || [])[i], d)}`).join(", ");
      [w.step_index + 1, `${w.kind} ${w.label}`, name, u.n, pm(u.gyro_dps, u.gyro_se_dps, 4),
       pm(u.accel_g, u.accel_se_g, 5)].forEach((v) => {
        const td = document.createElement("td");
        td.textContent = String(v);
        tr.appendChild(td);
      });
      body.appendChild(tr);
    }
    drawWindows();
  }
  function drawWindows() {
    const units = new Set();
    windows.forEach((w) => Object.keys(w.units || {}).forEach((n) => units.add(n)));
    const box = $("window-charts");
    for (const name of units) {
      const id = "windows-" + name.replace(/[^A-Za-z0-9_-]/g, "_");
      let holder = document.getElementById(id);
      if (!holder) {
        holder = document.createElement("div");
        holder.id = id;
        const h = document.createElement("h3");
        h.textContent = name;
        holder.appendChild(h);
        for (const kind of ["gyro", "accel"]) {
          const svg = document.createElementNS("http://www.w3.org/2000/svg", "svg");
          svg.setAttribute("viewBox", "0 0 640 160");
          svg.setAttribute("class", "chart " + kind);
          holder.appendChild(svg);
        }
        box.appendChild(holder);
      }
      const svgs = holder.querySelectorAll("svg");
      const mine = windows.filter((w) => w.units && w.units[name]);
      [["gyro_dps", "gyro_se_dps", "gyro [°/s]"], ["accel_g", "accel_se_g", "accel [g]"]]
        .forEach(([key, err, label], k) => {
          LiveChart.draw(svgs[k], {
            series: AXES.map((_a, i) => ({ cls: "s" + i, markers: true,
              points: mine.map((w) => [w.step_index + 1, w.units[name][key][i]]),
              errors: mine.map((w) => (w.units[name][err] || [])[i] || 0) })),
            legend: AXES.map((a, i) => ({ cls: "s" + i, label: a })),
            xLabel: "step", yLabel: label });
        });
    }
  }

  // --- events -------------------------------------------------------------------------------
  function apply(event) {
    switch (event.type) {
      case "snapshot": {
        view = event.view;
        setStatus(view.status, view.error);
        view.steps.forEach((s) => setStep(s.index, s.state));
        if (view.step_index >= 0) { $("step").textContent = view.step_index + 1; }
        $("time-left").textContent = duration(view.time_left_s);
        if (view.prompt) { showPrompt(view.prompt); } else { closePrompt(); }
        const history = event.history || {};
        if (history.trace) {
          const liveTail = trace.filter((p) => !history.trace.length ||
            p.time_s > history.trace[history.trace.length - 1].time_s);
          trace = [];
          history.trace.concat(liveTail).forEach(addTrace);
        }
        (history.windows || []).forEach(addWindow);
        showSignals(view.signals, view.time_left_s);
        break;
      }
      case "status": setStatus(event.status, event.error); break;
      case "step": setStep(event.index, event.state); break;
      case "prompt": showPrompt(event); break;
      case "prompt_closed": closePrompt(); break;
      case "log": appendLog(event.line); break;
      case "signals":
        if (Number.isInteger(event.step_index) && event.step_index >= 0) {
          view.step_index = event.step_index;
          $("step").textContent = event.step_index + 1;
        }
        showSignals(event.signals, event.time_left_s);
        break;
      case "window": addWindow(event); break;
      case "trace": addTrace(event); drawSoak(); break;
      case "safe_stop": appendLog(`safe stop: ${event.device}`); break;
      case "command_rejected": appendLog(`command refused: ${event.reason}`); break;
      case "end": setStatus(event.status, event.error); closePrompt(); break;
    }
  }
  async function send(path, fields) {
    const body = new FormData();
    for (const [k, v] of Object.entries(fields)) {
      if (v !== null && v !== undefined) { body.append(k, String(v)); }
    }
    const response = await fetch(`/runs/${encodeURIComponent(runId)}/${path}`, {
      method: "POST", body, credentials: "same-origin",
      headers: { "X-CSRF-Token": csrf, "Accept": "application/json" },
    });
    const answer = await response.json().catch(() => ({ error: response.statusText }));
    return { ok: response.ok, status: response.status, error: answer.error };
  }
  async function command(path, fields) {
    const got = await send(path, fields);
    if (!got.ok) { appendLog(`${path} refused: ${got.error}`); }
    return got.ok;
  }
  // An abort names the step the page shows; when the run has moved on meanwhile (409) it is
  // sent again for the step the page shows now — stopping is always safe (docs/web-runs.md).
  async function abortRun() {
    for (let attempt = 0; attempt < 10 && live.has(view.status); attempt++) {
      const shown = view.step_index >= 0 ? view.step_index : null;
      const got = await send("abort", { step_index: shown });
      if (got.ok) { return; }
      appendLog(`abort refused: ${got.error}`);
      if (got.status !== 409) { return; }
      await new Promise((resolve) => setTimeout(resolve, 200));
    }
  }
  function answer(confirmed) {
    if (!prompt) { return; }
    command("answer", { prompt_id: prompt.prompt_id, step_index: prompt.step_index,
                        confirmed, note: $("prompt-note").value });
    closePrompt();
  }
  if ($("confirm")) {  // the roles that answer (an observer only sees the check)
    $("confirm").addEventListener("click", () => answer(true));
    $("refuse").addEventListener("click", () => answer(false));
    $("prompt").addEventListener("cancel", (e) => e.preventDefault());  // Esc is no answer
  } else {
    $("prompt-hide").addEventListener("click", () => $("prompt").close());
  }
  const abort = $("abort");
  if (abort) {
    abort.addEventListener("click", () => {
      if (window.confirm("Stop the run safely now?")) { abortRun(); }
    });
  }
  const resume = $("resume");
  if (resume) {
    resume.addEventListener("click", async () => {
      resume.disabled = true;
      const ok = await command("resume", {});
      resume.disabled = false;
      if (ok) { setStatus("starting"); connect(); }
    });
  }
  setStatus(view.status);
  showSignals(view.signals, view.time_left_s);

  let delay = 500;
  let socket = null;
  function connect() {
    if (socket && socket.readyState <= 1) { return; }
    const scheme = location.protocol === "https:" ? "wss:" : "ws:";
    socket = new WebSocket(`${scheme}//${location.host}/ws/runs/${encodeURIComponent(runId)}`);
    socket.onopen = () => { $("connection").textContent = "live"; delay = 500; };
    socket.onmessage = (message) => apply(JSON.parse(message.data));
    socket.onclose = (closed) => {
      socket = null;
      if (closed.code === 4401) { location.href = "/login?next=" + encodeURIComponent(location.pathname); return; }
      if (closed.code >= 4400 || !live.has(view.status)) {
        $("connection").textContent = live.has(view.status) ? `disconnected (${closed.code})` : "ended";
        return;
      }
      $("connection").textContent = `reconnecting in ${(delay / 1000).toFixed(1)} s`;
      setTimeout(connect, delay);
      delay = Math.min(delay * 2, 10000);
    };
  }
  connect();
})();
