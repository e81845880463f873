// The mouse: drag the light on the lit sphere; orbit (drag) and zoom (wheel) the 3D lobe and the lit object.

import * as store from "./store.js";
import { canvasOf } from "./dom.js";
import { DEG } from "./numbers.js";
import { setSetting } from "./settings.js";

export function setupMouse() {
  const sphere = canvasOf("sphere");
  const moveLight = (ev) => {
    const r = sphere.getBoundingClientRect();
    const x = (ev.clientX - r.left) * sphere.width / r.width, y = (ev.clientY - r.top) * sphere.height / r.height;
    const sphereData = store.get("viewData").sphere;
    const T = (sphereData && sphereData.tiles) || [];
    for (const t of T) {
      if (x < t.x || x >= t.x + t.w || y >= t.h) continue;
      const px = ((x - t.x) / t.w * 2 - 1) * 1.06, py = -(y / t.h * 2 - 1) * 1.06;
      const r2 = px * px + py * py;
      if (r2 >= 1) return;
      // the light along the normal under the cursor: that point is lit head-on
      const nz = Math.sqrt(1 - r2);
      setSetting("light-theta", Math.round(Math.acos(nz) / DEG * 2) / 2);
      setSetting("light-phi", Math.round(((Math.atan2(py, px) / DEG + 360) % 360) * 2) / 2);
      store.changed("sphere");
      return;
    }
  };
  let dragging = false;
  sphere.addEventListener("pointerdown", (e) => { dragging = true; sphere.setPointerCapture(e.pointerId); moveLight(e); });
  sphere.addEventListener("pointermove", (e) => { if (dragging) moveLight(e); });
  sphere.addEventListener("pointerup", () => { dragging = false; });
  for (const name of ["lobe3d", "object"]) {
    const c = canvasOf(name);
    let last = null;
    c.addEventListener("pointerdown", (e) => { last = [e.clientX, e.clientY]; c.setPointerCapture(e.pointerId); });
    c.addEventListener("pointermove", (e) => {
      if (!last) return;
      store.update("orbit", (orbit) => {
        const o = orbit[name];
        o.yaw += (e.clientX - last[0]) * 0.5;
        o.pitch = Math.max(-89, Math.min(89, o.pitch + (e.clientY - last[1]) * 0.5));
      });
      last = [e.clientX, e.clientY];
      store.changed();
    });
    c.addEventListener("pointerup", () => { last = null; });
    c.addEventListener("wheel", (e) => {
      e.preventDefault();
      store.update("orbit", (orbit) => { orbit[name].zoom = Math.max(0.2, Math.min(8, orbit[name].zoom * Math.exp(-e.deltaY * 0.001))); });
      store.changed();
    }, { passive: false });
  }
}
