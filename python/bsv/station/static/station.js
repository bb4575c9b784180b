// BSV Station: polls the job's progress (GET /api/jobs/ID) on the job page and refreshes the rig page's
// live camera frames; no build step.
(function () {
  // rig page: refresh the live alignment frames
  document.querySelectorAll("img.live").forEach((img) => {
    setInterval(() => { img.src = img.dataset.src + "?t=" + Date.now(); }, 2000);
  });
})();
(function () {
  const box = document.getElementById("job");
  if (!box) return;
  const id = box.dataset.job;
  function show(j) {
    document.getElementById("bar").value = j.progress;
    document.getElementById("state").textContent = j.state;
    document.getElementById("step").textContent = j.step;
    const msg = document.getElementById("message");
    if (j.message) { msg.textContent = j.message; msg.hidden = false; }
    const links = document.getElementById("links");
    let html = "";
    if (j.session_id) html += '<a href="/sessions/' + j.session_id + '" id="session-link">session #' + j.session_id + "</a>";
    if (j.result_id) html += ' · <a href="/results/' + j.result_id + '/files/report.html" id="report-link">report</a>';
    if (j.state === "done" || j.state === "failed") html += ' · <a href="/subjects/' + j.subject_id + '" id="subject-link">back to the subject</a>';
    links.innerHTML = html;
  }
  function poll() {
    fetch("/api/jobs/" + id, { credentials: "same-origin" })
      .then((r) => r.json())
      .then((j) => {
        show(j);
        const over = j.state === "done" || j.state === "failed";
        if (!over) setTimeout(poll, 1000);
        else if (box.dataset.kind === "preview" && box.dataset.finished === "no") location.reload();
      })
      .catch(() => setTimeout(poll, 3000));
  }
  poll();
})();
