/**
 * The 3D view: the interpolated surface of every component, lit and
 * orbitable, in physical units. Loaded on demand so the tracing screen
 * starts without three.js.
 */
import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import type { Mesh } from "./api";
import { taubin } from "./smooth";

/** One surface to show. */
export interface Surface {
  /** Label name (legend). */
  name: string;
  /** `#rrggbb`. */
  color: string;
  /** The mesh. */
  mesh: Mesh;
}

/** A three.js viewer bound to a container element. */
export class Viewer3D {
  private renderer: THREE.WebGLRenderer;
  private scene = new THREE.Scene();
  private camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1e6);
  private controls: OrbitControls;
  private group = new THREE.Group();
  private ro: ResizeObserver;
  private disposed = false;

  constructor(private host: HTMLElement) {
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.renderer.setClearColor(0x15171c);
    host.appendChild(this.renderer.domElement);
    this.scene.add(new THREE.AmbientLight(0xffffff, 0.5));
    const key = new THREE.DirectionalLight(0xffffff, 1.6);
    key.position.set(1, 1.5, 2);
    this.camera.add(key);
    this.scene.add(this.camera);
    this.scene.add(this.group);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener("change", () => this.render());
    this.ro = new ResizeObserver(() => this.resize());
    this.ro.observe(host);
    this.resize();
  }

  /** Replace the surfaces shown and frame them. */
  show(surfaces: Surface[]): void {
    for (const c of [...this.group.children]) {
      this.group.remove(c);
      const m = c as THREE.Mesh;
      m.geometry?.dispose();
      (m.material as THREE.Material | undefined)?.dispose();
    }
    // Inner structures are drawn last and the outer ones see-through, so nuclei show inside cells.
    surfaces.forEach((s, n) => {
      if (s.mesh.indices.length === 0) return;
      const g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.Float32BufferAttribute(taubin(s.mesh.vertices, s.mesh.indices), 3));
      g.setIndex(s.mesh.indices);
      g.computeVertexNormals();
      const outer = n < surfaces.length - 1;
      const mat = new THREE.MeshPhongMaterial({
        color: new THREE.Color(s.color),
        side: THREE.DoubleSide,
        transparent: outer,
        opacity: outer ? 0.35 : 1,
        depthWrite: !outer,
        shininess: 40,
      });
      const mesh = new THREE.Mesh(g, mat);
      mesh.renderOrder = n;
      this.group.add(mesh);
    });
    const box = new THREE.Box3().setFromObject(this.group);
    if (!box.isEmpty()) {
      const c = box.getCenter(new THREE.Vector3());
      const r = box.getSize(new THREE.Vector3()).length() / 2 || 1;
      this.controls.target.copy(c);
      this.camera.near = r / 100;
      this.camera.far = r * 100;
      this.camera.position.copy(c).add(new THREE.Vector3(r * 1.2, -r * 1.6, r * 1.4));
      this.camera.up.set(0, 0, 1);
      this.camera.updateProjectionMatrix();
      this.controls.update();
    }
    this.render();
  }

  private resize(): void {
    const w = Math.max(1, this.host.clientWidth);
    const hgt = Math.max(1, this.host.clientHeight);
    this.renderer.setSize(w, hgt);
    this.camera.aspect = w / hgt;
    this.camera.updateProjectionMatrix();
    this.render();
  }

  /** Draw one frame. */
  render(): void {
    if (!this.disposed) this.renderer.render(this.scene, this.camera);
  }

  /** Release GPU resources. */
  dispose(): void {
    this.disposed = true;
    this.ro.disconnect();
    this.controls.dispose();
    this.renderer.dispose();
    this.renderer.domElement.remove();
  }
}
