// The report's interactive view of the fitted material (docs/report.md,
// "The material, interactive"). Bundled with three.js by esbuild into one
// classic script at build time (viewer.cmake: Chromium runs no ES module
// from file://), copied into each report as viewer/three_viewer.js.
//
// It reads window.clayfitMaterial (viewer/material.js: the glsl export as a
// classic script) and the canvas' data-scene (written by report_viewer.c:
// directional lights in the starting camera's frame, exposed), renders the
// sphere with the exact material into a float target, tone-maps it as
// clayfit's PNG is (cf_sphere_tone, then sRGB) and lets the user orbit the
// camera. #clayfit-view-status says what happened (the browser test reads it).
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';

const TONE_VERTEX = `
varying vec2 vUv;
void main() {
  vUv = uv;
  gl_Position = vec4(position.xy, 0.0, 1.0);
}`;

// cf_sphere_tone (thumbnail.c) and the sRGB curve; what the material did not
// cover (alpha 0) is the view's background, toned as clayfit's PNG tones it
const TONE_FRAGMENT = `
uniform sampler2D radiance;
uniform float background;
uniform float knee;
varying vec2 vUv;
float tone(float x) {
  if (!(x > 0.0)) return 0.0;
  if (x <= knee) return x;
  float room = 1.0 - knee;
  return knee + room * (1.0 - exp(-(x - knee) / room));
}
float srgb(float x) {
  return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}
void main() {
  vec4 r = texture2D(radiance, vUv);
  vec3 c = r.a > 0.5 ? r.rgb : vec3(background);
  gl_FragColor = vec4(srgb(tone(c.r)), srgb(tone(c.g)), srgb(tone(c.b)), 1.0);
}`;

function say(text, rect) {
  const p = document.getElementById('clayfit-view-status');
  if (!p) return;
  p.textContent = text;
  if (rect) {
    const r = rect.getBoundingClientRect();
    p.dataset.rect = [r.left + window.scrollX, r.top + window.scrollY, r.width, r.height]
      .map(Math.round).join(',');
  }
}

function start() {
  const canvas = document.getElementById('clayfit-view');
  if (!canvas) return;
  const made = window.clayfitMaterial;
  if (!made) {
    say('interactive view failed: viewer/material.js did not load');
    return;
  }
  const scene = JSON.parse(canvas.dataset.scene);
  let shaderError = '';
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false,
                                             preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(scene.size, scene.size, false);
  renderer.debug.onShaderError = (gl, program, vertex, fragment) => {
    shaderError = [gl.getProgramInfoLog(program), gl.getShaderInfoLog(vertex),
                   gl.getShaderInfoLog(fragment)].filter(Boolean).join(' ').trim() ||
                  'it did not link';
  };
  const type = renderer.extensions.has('EXT_color_buffer_float') ? THREE.FloatType
                                                                  : THREE.HalfFloatType;
  const target = new THREE.WebGLRenderTarget(scene.size, scene.size, {
    type, minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter });

  // the sphere (radius 1 at the origin) fills scene.radius of the half side,
  // as in clayfit's view; orthographic, looking down -z
  const half = 1 / scene.radius;
  const camera = new THREE.OrthographicCamera(-half, half, half, -half, 0.1, 100);
  camera.position.set(0, 0, 10);
  camera.lookAt(0, 0, 0);
  // the material takes clayfit.maxLights lights: more are added in passes
  // (radiance is linear in the lights), one mesh per group of lights,
  // blended additively into the float target; front faces only, so that
  // each pixel is shaded once per group. A mesh a little larger than the
  // sphere covers its silhouette; the material intersects each pixel's ray
  // with the exact sphere.
  const world = new THREE.Scene();
  const geometry = new THREE.SphereGeometry(1.05, 96, 48);
  const most = made.clayfit.maxLights;
  for (let first = 0; first < scene.lights.length; first += most) {
    const material = made.createClayfitMaterial(THREE, {
      lights: scene.lights.slice(first, first + most)
        .map((l) => ({ direction: l.direction, irradiance: l.irradiance })),
      sphere: { center: [0, 0, 0], radius: 1 },
      exposure: 1,
    });
    material.blending = THREE.AdditiveBlending;
    material.depthTest = false;
    material.depthWrite = false;
    world.add(new THREE.Mesh(geometry, material));
  }

  const tone = new THREE.ShaderMaterial({
    uniforms: { radiance: { value: target.texture }, background: { value: scene.background },
                knee: { value: scene.knee } },
    vertexShader: TONE_VERTEX, fragmentShader: TONE_FRAGMENT, depthTest: false,
    depthWrite: false });
  const quad = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), tone);
  quad.frustumCulled = false;
  const screen = new THREE.Scene();
  screen.add(quad);
  const screenCamera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);

  function draw() {
    renderer.setRenderTarget(target);
    renderer.setClearColor(0x000000, 0);
    renderer.clear();
    renderer.render(world, camera);
    renderer.setRenderTarget(null);
    renderer.render(screen, screenCamera);
    if (shaderError) say('interactive view failed: the material\'s shader: ' + shaderError, canvas);
  }
  const controls = new OrbitControls(camera, canvas);
  controls.enablePan = false;
  controls.addEventListener('change', draw);
  draw();
  if (!shaderError)
    say(`interactive view: drawn (three.js r${THREE.REVISION}, WebGL 2, ` +
        `${scene.lights.length} lights); drag to rotate`, canvas);
  window.addEventListener('load', () => {
    if (!shaderError) say(document.getElementById('clayfit-view-status').textContent, canvas);
  });
}

try {
  start();
} catch (e) {
  say('interactive view failed: ' + e.message);
}
