// The page's one WebGL 2 context. Its canvas is off-screen: each view is a 2D canvas the GL
// image is copied into (blit). `gl` and `glCanvas` are live bindings, set once by initGL().

export let gl = null;
export let glCanvas = null;

/** Create the context on a 560x420 off-screen canvas; null when WebGL 2 is missing. */
export function initGL() {
  glCanvas = document.createElement("canvas");
  glCanvas.width = 560; glCanvas.height = 420;
  gl = glCanvas.getContext("webgl2", { antialias: false, preserveDrawingBuffer: true, depth: true });
  return gl;
}

/** A linked program from GLSL ES sources; an Error naming the stage and the compiler's log. */
export function compileProgram(vertSource, fragSource) {
  const mk = (type, src) => {
    const s = gl.createShader(type);
    gl.shaderSource(s, src);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) {
      const log = gl.getShaderInfoLog(s) || "compile failed";
      gl.deleteShader(s);
      throw new Error((type === gl.VERTEX_SHADER ? "vertex: " : "fragment: ") + log.trim());
    }
    return s;
  };
  const vs = mk(gl.VERTEX_SHADER, vertSource);
  const fs = mk(gl.FRAGMENT_SHADER, fragSource);
  const prog = gl.createProgram();
  gl.attachShader(prog, vs);
  gl.attachShader(prog, fs);
  gl.linkProgram(prog);
  gl.deleteShader(vs);
  gl.deleteShader(fs);
  if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) {
    const log = gl.getProgramInfoLog(prog) || "link failed";
    throw new Error("link: " + log.trim());
  }
  prog._u = {};
  return prog;
}

/** A uniform's location in `prog`, cached. */
export function U(prog, name) {
  if (!(name in prog._u)) prog._u[name] = gl.getUniformLocation(prog, name);
  return prog._u[name];
}

/** An RGBA32F w x h texture (nearest, clamped), filled from `data` or empty (null). */
export function makeFloatTexture(w, h, data) {
  const tex = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, tex);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, w, h, 0, gl.RGBA, gl.FLOAT, data);
  return tex;
}

/** Grow the GL canvas to at least w x h (never shrinks it). */
export function glSize(w, h) {
  if (glCanvas.width < w || glCanvas.height < h) {
    glCanvas.width = Math.max(glCanvas.width, w);
    glCanvas.height = Math.max(glCanvas.height, h);
  }
}

/** Copy the GL canvas's last w x h image (its top-left) into a 2D context at (dx, dy). */
export function blit(ctx, w, h, dx, dy) {
  ctx.drawImage(glCanvas, 0, glCanvas.height - h, w, h, dx || 0, dy || 0, w, h);
}
