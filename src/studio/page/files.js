// Files: Open (the workspace's pictures, meshes, outlines and projects, and recovered work),
// Save (Ctrl+S) and Save as, a file dropped on the page (stored in the workspace, then opened
// or drawn on the mesh), exports in the background, the unsaved-changes mark, and a warning
// before closing the page while changes are unsaved.

import { S, $, redraw } from "./view.js";
import { send, upload, on } from "./net.js";
import { confirmDialog, promptDialog } from "./panels.js";
import { sliderTime } from "./timeline.js";

const when = (seconds) => new Date(seconds * 1000).toLocaleString();

// The Open dialog: files by kind, and recovered work with Restore / Put aside.
$("open").onclick = () => { S.filesFor = "open"; send({ op: "list_files" }); };
on("files", (msg) => {
  // A list asked for by the drawing dialog is its own.
  if (S.filesFor === "drawing") { S.filesFor = null; return; }
  const list = $("open-list");
  list.textContent = "";
  const rows = [];
  for (const r of msg.recovered) {
    rows.push({ text: `recovered work${r.project ? ` of ${r.project}` : ""} from ${when(r.saved_at)}: ${r.keyframes} keyframes, ${r.vertices} vertices${r.source && r.source !== r.project ? `, from ${r.source}` : ""}`, open: () => send({ op: "recover", name: r.name }) });
  }
  for (const f of msg.files) rows.push({ text: `${f.name} (${f.kind}, ${(f.bytes / 1024).toFixed(0)} KB)`, open: () => openFile(f.name) });
  if (!rows.length) list.textContent = `No pictures, meshes, outlines or projects in ${msg.workspace}. Drop a file on the page to add one.`;
  for (const row of rows) {
    const b = document.createElement("button");
    b.className = "file";
    b.textContent = row.text;
    b.onclick = () => { $("open-dialog").close(); row.open(); };
    list.appendChild(b);
  }
  $("open-where").textContent = msg.workspace;
  if (!$("open-dialog").open) $("open-dialog").showModal();
});
$("open-close").onclick = () => $("open-dialog").close();

async function openFile(name) {
  if (S.state && S.state.dirty && !(await confirmDialog(`Open ${name}? This project's unsaved changes stay one Undo away (and in the autosave).`, "Open"))) return;
  send({ op: "open", name });
}

export async function save() {
  if (S.state && S.state.project) send({ op: "save" });
  else await saveAs();
}
export async function saveAs() {
  const name = await promptDialog("Save the project in the workspace as", (S.state && S.state.project) || "project.json");
  if (!name) return;
  S.pendingSave = name.toLowerCase().endsWith(".json") ? name : `${name}.json`;
  send({ op: "save", name: S.pendingSave });
}
$("save").onclick = save;
$("save-as").onclick = saveAs;
// "exists: save over it?" asks before replacing another file.
on("error", async (msg) => {
  if (S.pendingSave && msg.message && msg.message.startsWith(`${S.pendingSave} exists`)) {
    const name = S.pendingSave;
    S.pendingSave = null;
    msg.handled = true;
    if (await confirmDialog(`${name} exists. Replace it?`, "Replace")) send({ op: "save", name, overwrite: true });
  }
});
on("state", (st) => {
  if (st.dirty === false) S.pendingSave = null;
  const name = st.project || st.source || "untitled";
  document.title = `${st.dirty ? "● " : ""}${name} — bdmorph studio`;
  $("dirty").hidden = !st.dirty;
  $("doc-name").textContent = name;
  const banner = $("banner-recovered");
  const r = st.recovered[0];
  banner.hidden = !r;
  if (r) {
    $("recovered-text").textContent = `Unsaved work${r.project ? ` on ${r.project}` : ""} a studio in this folder kept when it stopped (${when(r.saved_at)}): ${r.keyframes} keyframes, ${r.vertices} vertices${r.source && r.source !== r.project ? `, from ${r.source}` : ""}${st.recovered.length > 1 ? ` (and ${st.recovered.length - 1} more in Open)` : ""}.`;
    $("recovered-restore").onclick = () => send({ op: "recover", name: r.name });
    $("recovered-aside").onclick = () => send({ op: "discard", name: r.name });
  }
});

// (Scripted tests that reload on purpose set studio.leaving.)
window.addEventListener("beforeunload", (e) => {
  if (S.state && S.state.dirty && !S.leaving) { e.preventDefault(); e.returnValue = ""; }
});

// A file dropped on the page goes to the workspace, then is opened; a picture dropped on a
// mesh may instead be drawn on it.
window.addEventListener("dragover", (e) => { e.preventDefault(); document.body.classList.add("dropping"); });
window.addEventListener("dragleave", () => document.body.classList.remove("dropping"));
window.addEventListener("drop", async (e) => {
  e.preventDefault();
  document.body.classList.remove("dropping");
  const file = e.dataTransfer && e.dataTransfer.files[0];
  if (!file) return;
  let then = "open";
  if (/\.(png|jpe?g)$/i.test(file.name) && S.state) {
    const choice = await confirmDialog(`${file.name}: open it as a new project (meshed by its subject), or draw it on this mesh?`, "Open as new", "Draw on this mesh");
    if (choice === false) return;
    then = choice === "other" ? "attach" : "open";
  }
  if (then === "open" && S.state && S.state.dirty && !(await confirmDialog(`Open ${file.name}? This project's unsaved changes stay one Undo away.`, "Open"))) return;
  upload(file.name, await file.arrayBuffer(), then);
});
$("attach").onclick = () => $("attach-file").click();
$("attach-file").addEventListener("change", async () => {
  const file = $("attach-file").files[0];
  if (!file) return;
  upload(file.name, await file.arrayBuffer(), "attach");
  $("attach-file").value = "";
});

// The export dialog: format, name, size (empty: the subject's aspect), range (the whole
// animation, as `bdmorph export` makes it, the loop range, or frames given; the dialog names
// the seconds and frames it will export), background (transparent for the formats that keep
// it).
const ALPHA = new Set(["apng", "webp", "sheet", "frames", "still"]);
function syncExport() {
  const f = $("export-format").value;
  const alpha = ALPHA.has(f);
  const transparent = $("export-background").querySelector('option[value="transparent"]');
  transparent.disabled = !alpha;
  if (!alpha && $("export-background").value === "transparent") $("export-background").value = "white";
  $("export-colour").hidden = $("export-background").value !== "colour";
  const total = S.state ? Math.round(S.state.duration * S.state.fps) + 1 : 0;
  $("export-count").textContent = total ? `of 0 to ${total - 1}` : "";
  $("export-range").querySelector('option[value="loop"]').disabled = !(S.state && S.state.loop_range);
  if ($("export-range").value === "loop" && !(S.state && S.state.loop_range)) $("export-range").value = "all";
  $("export-frames").hidden = $("export-range").value !== "frames";
  const frames = exportFrames();
  // A frame's time: the frames are spread evenly over the animation.
  const secs = (i) => (total > 1 ? ((i / (total - 1)) * S.state.duration).toFixed(2) : "0.00");
  $("export-range-text").textContent = f === "still" ? "the frame shown"
    : !frames ? "" : f === "png" ? `five frames of ${secs(frames[0])}-${secs(frames[1])} s`
    : `${secs(frames[0])}-${secs(frames[1])} s, ${frames[1] - frames[0] + 1} frames`;
  $("export-hint").textContent = {
    gif: "an animated GIF, opaque", mp4: "H.264 video, opaque",
    apng: "lossless, with transparency: browsers, FFmpeg, editors",
    webp: "lossless, with transparency: browsers, game engines",
    sheet: "one PNG of every frame on a grid, and a JSON beside it (frame rectangles, size, fps) for game engines",
    frames: "a folder of PNG frames (frame_0000.png, ...)",
    png: "five frames coloured by distortion", html: "a self-contained viewer", obj: "a folder of OBJ meshes",
    still: "the frame shown, as a PNG",
  }[f] || "";
}
$("export-format").addEventListener("change", () => {
  const f = $("export-format").value;
  const ext = { gif: ".gif", mp4: ".mp4", apng: ".apng", webp: ".webp", sheet: ".png", png: ".png", html: ".html", obj: "", frames: "", still: ".png" }[f];
  // Each format its own default name: one export never takes another's place.
  $("export-name").value = { still: "frame.png", sheet: "sheet.png", png: "strip.png", frames: "animation-png", obj: "animation-obj" }[f] ?? "animation" + ext;
  syncExport();
});
$("export-background").addEventListener("change", syncExport);
for (const id of ["export-range", "export-first", "export-last"]) $(id).addEventListener("input", syncExport);
// The frames [first, last] the range chosen exports (of the animation's 0 to total - 1), or
// null when they are not given yet.
function exportFrames() {
  const st = S.state;
  if (!st) return null;
  const total = Math.round(st.duration * st.fps) + 1;
  const which = $("export-range").value;
  if (which === "loop" && st.loop_range) {
    // As `bdmorph export --loop-range` picks them.
    const at = (t) => (st.duration > 0 ? Math.min(Math.round((Math.min(t, st.duration) / st.duration) * (total - 1)), total - 1) : 0);
    const [a, b] = st.loop_range.map(at);
    return [a, Math.max(a, b)];
  }
  if (which === "frames") {
    const num = (el) => (el.value !== "" ? Number(el.value) : null);
    const first = num($("export-first")) ?? 0, last = num($("export-last")) ?? total - 1;
    return [first, last];
  }
  return [0, total - 1];
}
$("export-open").onclick = () => {
  syncExport();
  $("export-dialog").showModal();
};
$("export-close").onclick = () => $("export-dialog").close();
$("export").onclick = () => {
  const format = $("export-format").value;
  const request = { op: "export", format, name: $("export-name").value };
  // A screenshot is of what is shown: the scrubbed frame, or the keyframe shown.
  if (format === "still" && S.showing === "frame") request.time = sliderTime();
  const w = $("export-width").value, h = $("export-height").value;
  if (w !== "" || h !== "") {
    if (w === "" || h === "") { S.errors.push("give both the width and the height, or neither"); redraw(); return; }
    request.size = [Number(w), Number(h)];
  }
  // The whole animation is sent without a range (as `bdmorph export` makes it).
  if ($("export-range").value !== "all") {
    const frames = exportFrames();
    if (frames) request.range = frames;
  }
  const bg = $("export-background").value;
  request.background = bg === "colour" ? $("export-colour").value : bg;
  S.pendingExport = request;
  send(request);
  $("export-dialog").close();
};
// An export onto a file or folder that exists asks first; nothing is replaced without a yes.
on("exists", async (msg) => {
  const asked = S.pendingExport;
  if (!asked || asked.name !== msg.name) return;
  S.pendingExport = null;
  if (await confirmDialog(`${msg.path} exists. Replace it with this export?`, "Replace")) send({ ...asked, overwrite: true });
});
