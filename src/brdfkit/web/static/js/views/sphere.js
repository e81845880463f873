// The lit sphere: one tile per visible BRDF, ray-cast per pixel by SPHERE_MAIN, a directional light.

import { canvasOf } from "../dom.js";
import { gl, glSize, U } from "../gl.js";
import { BACKGROUND, DEG, srgbEncode } from "../numbers.js";
import { getSetting, num } from "../settings.js";
import { bindMaterial, getProgram, intConstants, sourceKey } from "../brdfs.js";
import { visiblePanels } from "../panels.js";
import { blitTiles, fitTiles, reportDrawError } from "./plot.js";

function lightDir() {
  const th = num("light-theta") * DEG, ph = num("light-phi") * DEG;
  return [Math.sin(th) * Math.cos(ph), Math.sin(th) * Math.sin(ph), Math.cos(th)];
}

export function drawSphere(canvasArg) {
  const canvas = canvasArg || canvasOf("sphere");
  const ctx = canvas.getContext("2d");
  const list = visiblePanels();
  const T = fitTiles(canvas, list.length);
  const bgByte = Math.round(255 * srgbEncode(BACKGROUND));  // the spheres' own background, no band around them
  ctx.fillStyle = `rgb(${bgByte}, ${bgByte}, ${bgByte})`; ctx.fillRect(0, 0, canvas.width, canvas.height);
  const size = T[0].w;
  glSize(size * list.length, size);
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  gl.disable(gl.DEPTH_TEST);
  const L = lightDir();
  const scale = Math.PI * Math.pow(2, num("exposure"));
  list.forEach((panel, i) => {
    try {
      const prog = getProgram(sourceKey(panel.model), "sphere", intConstants(panel.model, panel.params()));
      gl.useProgram(prog);
      gl.viewport(i * size, 0, size, size);
      gl.uniform4f(U(prog, "bkw_viewport"), i * size, 0, size, size);
      gl.uniform3f(U(prog, "bkw_light"), L[0], L[1], L[2]);
      gl.uniform1f(U(prog, "bkw_scale"), scale);
      gl.uniform1i(U(prog, "bkw_tangent"), parseInt(getSetting("tangent"), 10));
      const bg = srgbEncode(BACKGROUND);
      gl.uniform3f(U(prog, "bkw_background"), bg, bg, bg);
      bindMaterial(prog, panel.model, panel.params());
      gl.drawArrays(gl.TRIANGLES, 0, 3);
    } catch (e) { reportDrawError(e); }
  });
  blitTiles(ctx, "sphere", list, T, size, (panel) => panel.model);
}
