// GLSL sources the page adds to a BRDF's own (which defines vec3 brdf(vec3 wi, vec3 wo)):
// the mains of the per-pixel views, and the renderer's pipeline assembled from render/shaders.

export const VERT = `#version 300 es
void main() {
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
`;
export const SRGB_GLSL = `
vec3 bkw_srgb(vec3 c) {  // one vector pow, not three scalar ones
  c = clamp(c, 0.0, 1.0);
  return mix(1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, 12.92 * c, lessThanEqual(c, vec3(0.0031308)));
}
`;
export const SPHERE_MAIN = `
uniform vec4 bkw_viewport;     // x, y, w, h in pixels
uniform vec3 bkw_light;        // unit, view space (viewer along +z)
uniform float bkw_scale;       // light irradiance x 2^exposure
uniform int bkw_tangent;       // 0: tangents along latitudes, 1: along longitudes
uniform vec3 bkw_background;  // sRGB-encoded (srgbEncode on the page)
out vec4 bkw_color;
${SRGB_GLSL}
void main() {
  vec2 p = ((gl_FragCoord.xy - bkw_viewport.xy) / bkw_viewport.zw * 2.0 - 1.0) * 1.06;
  float r2 = dot(p, p);
  if (r2 >= 1.0) { bkw_color = vec4(bkw_background, 1.0); return; }
  vec3 n = vec3(p, sqrt(1.0 - r2));
  vec3 axis = bkw_tangent == 0 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
  vec3 t = cross(axis, n);
  float tl = length(t);
  t = tl > 1e-6 ? t / tl : vec3(1.0, 0.0, 0.0);
  if (bkw_tangent == 1) t = -t;
  vec3 b = cross(n, t);
  vec3 L = bkw_light;
  vec3 V = vec3(0.0, 0.0, 1.0);
  vec3 wi = normalize(vec3(dot(L, t), dot(L, b), dot(L, n)));
  vec3 wo = normalize(vec3(dot(V, t), dot(V, b), dot(V, n)));
  vec3 c = brdf(wi, wo) * max(wi.z, 0.0) * bkw_scale;
  float r = sqrt(r2);
  float a = clamp((1.0 - r) / max(fwidth(r), 1e-6), 0.0, 1.0);
  bkw_color = vec4(mix(bkw_background, bkw_srgb(c), a), 1.0);
}
`;
// θh × θd image at φd (Rusinkiewicz 1998, φh = 0): h = (sin θh, 0, cos θh); d in h's frame
export const SLICE_MAIN = `
uniform vec4 bkw_viewport;
uniform float bkw_phi_d;
uniform float bkw_scale;       // 2^exposure (linear) or the plot's maximum (log)
uniform int bkw_log;
uniform int bkw_channel;       // 0 rgb, 1 r, 2 g, 3 b, 4 luminance
uniform int bkw_ndotl;
out vec4 bkw_color;
${SRGB_GLSL}
void main() {
  vec2 uv = (gl_FragCoord.xy - bkw_viewport.xy) / bkw_viewport.zw;
  float th = uv.x * BK_HALF_PI, td = uv.y * BK_HALF_PI;
  vec3 h = vec3(sin(th), 0.0, cos(th));
  vec3 bx = vec3(cos(th), 0.0, -sin(th));
  vec3 d = vec3(sin(td) * cos(bkw_phi_d), sin(td) * sin(bkw_phi_d), cos(td));
  vec3 wi = normalize(d.x * bx + vec3(0.0, d.y, 0.0) + d.z * h);
  vec3 wo = normalize(2.0 * dot(h, wi) * h - wi);
  vec3 f = brdf(wi, wo);
  if (bkw_ndotl == 1) f *= max(wi.z, 0.0);
  if (bkw_channel == 1) f = vec3(f.r);
  else if (bkw_channel == 2) f = vec3(f.g);
  else if (bkw_channel == 3) f = vec3(f.b);
  else if (bkw_channel == 4) f = vec3(dot(f, vec3(0.2126, 0.7152, 0.0722)));
  vec3 c;
  if (bkw_log == 1) c = clamp(1.0 + log(max(f, vec3(1e-30)) / bkw_scale) / log(10.0) / 4.0, 0.0, 1.0);
  else c = f * bkw_scale;
  bkw_color = vec4(bkw_srgb(c), 1.0);
}
`;
export const EVAL_MAIN = `
uniform highp sampler2D bkw_wi;
uniform highp sampler2D bkw_wo;
out vec4 bkw_value;
void main() {
  ivec2 ij = ivec2(gl_FragCoord.xy);
  vec3 wi = texelFetch(bkw_wi, ij, 0).xyz;
  vec3 wo = texelFetch(bkw_wo, ij, 0).xyz;
  bkw_value = vec4(brdf(wi, wo), 1.0);
}
`;

/** A model's source with its integer uniforms made constants: `uniform int u_x;` becomes
 * `const int u_x = v;` (consts: {u_x: v}), so the compiler drops the branches not taken. */
export function specialise(src, consts) {
  for (const [n, v] of Object.entries(consts || {})) {
    const re = new RegExp(`^uniform int ${n};`, "m");
    src = src.replace(re, `const int ${n} = ${v};`);  // (a source without the line keeps its uniform)
  }
  return src;
}

export const PIPELINE_FILES = ["pipeline_lights.glsl", "pipeline_vertex.glsl", "pipeline_fragment.glsl", "pipeline_brdf.glsl", "opengl_fixed.glsl"];

/** The renderer's pipeline as {vs, fs}, assembled as brdfkit.render.renderer.Renderer._program does
 * (GLSL ES 3.00 instead of 3.30; pinned to it by tests/test_web_js_twins.py).
 * kind: "obj-<shading>" (a BRDF, point lights), "ibl-<shading>" (a BRDF, an environment) or
 * "gl-<shading>" (the fixed-function model); files: file name -> text; brdfSource: the BRDF's GLSL. */
export function pipelineSources(kind, files, brdfSource) {
  const [what, shading] = kind.split("-");
  const F = files;
  for (const f of PIPELINE_FILES) if (F[f] === undefined) throw new Error(`shader file ${f} not loaded`);
  const where = what === "ibl" ? "ibl" : shading === "phong" ? "fragment" : "vertex";
  const defines = [];
  if (shading === "flat") defines.push("#define BKR_FLAT");
  defines.push({ vertex: "#define BKR_LIGHT_IN_VERTEX", fragment: "#define BKR_LIGHT_IN_FRAGMENT", ibl: "#define BKR_IBL" }[where]);
  // GLSL ES fragment shaders have no default float precision: declare it first (and
  // highp samplers: the environment and the MERL table are float textures)
  const head = "#version 300 es\n" + defines.join("\n")
    + "\nprecision highp float;\nprecision highp int;\nprecision highp sampler2D;\nprecision highp sampler3D;\n";
  let body;
  if (what === "gl") body = F["pipeline_lights.glsl"] + F["opengl_fixed.glsl"];
  else {
    body = brdfSource.replace(/^#version[^\n]*\n/, "") + F["pipeline_lights.glsl"];
    if (what === "ibl") {
      if (F["ibl.glsl"] === undefined) throw new Error("this server has no image-based lighting shaders");
      body += F["ibl_sampling.glsl"] + F["ibl.glsl"];
    } else body += F["pipeline_brdf.glsl"];
  }
  const vs = head + (where === "vertex" ? body : F["pipeline_lights.glsl"]) + F["pipeline_vertex.glsl"];
  const fs = head + (where !== "vertex" ? body : "") + F["pipeline_fragment.glsl"];
  return { vs, fs };
}
