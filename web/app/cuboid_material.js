// Geometry and material of the instanced cuboids.
//
// A box shows at most three faces to a viewer outside it. The geometry holds only the +x, +y
// and +z faces of a unit cube (6 triangles instead of 12); the vertex shader mirrors them per
// instance towards the camera (sign of camera − box centre per axis), so each cuboid costs half
// the triangles of a full box: what bounds a software rasteriser (SwiftShader, llvmpipe), and
// still saves work on a GPU. Shading is flat per face, computed per vertex; the fragment shader
// only writes the colour.

import * as THREE from 'three';

export function threeFaceBoxGeometry() {
  const positions = [];
  const normals = [];
  const indices = [];
  const face = (n, u, v) => {
    const base = positions.length / 3;
    for (const [a, b] of [[-1, -1], [1, -1], [1, 1], [-1, 1]]) {
      positions.push(0.5 * (n[0] + a * u[0] + b * v[0]), 0.5 * (n[1] + a * u[1] + b * v[1]), 0.5 * (n[2] + a * u[2] + b * v[2]));
      normals.push(...n);
    }
    indices.push(base, base + 1, base + 2, base, base + 2, base + 3);
  };
  face([1, 0, 0], [0, 1, 0], [0, 0, 1]);
  face([0, 1, 0], [0, 0, 1], [1, 0, 0]);
  face([0, 0, 1], [1, 0, 0], [0, 1, 0]);
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
  g.setAttribute('normal', new THREE.Float32BufferAttribute(normals, 3));
  g.setIndex(indices);
  return g;
}

const vertexShader = /* glsl */ `
  uniform float zCut;
  varying vec3 vColor;
  void main() {
    vec3 centre = (modelMatrix * instanceMatrix * vec4(0.0, 0.0, 0.0, 1.0)).xyz;
    if (centre.z - 0.5 * instanceMatrix[2][2] > zCut) {
      gl_Position = vec4(0.0, 0.0, 2.0, 1.0); // above the cut: every vertex outside the clip volume
      vColor = vec3(0.0);
      return;
    }
    vec3 side = sign(cameraPosition - centre);
    side = side + vec3(equal(side, vec3(0.0)));   // camera in a face plane: any side will do
    vec3 local = position * side;
    vec3 n = normal * side;
    float light = 0.58 + 0.34 * max(dot(n, normalize(vec3(0.35, -0.5, 1.0))), 0.0) + 0.10 * n.z - 0.04 * n.x;
    #ifdef USE_INSTANCING_COLOR
      vColor = instanceColor * light;
    #else
      vColor = vec3(light);
    #endif
    gl_Position = projectionMatrix * viewMatrix * modelMatrix * instanceMatrix * vec4(local, 1.0);
  }
`;

const fragmentShader = /* glsl */ `
  uniform float opacity;
  varying vec3 vColor;
  void main() {
    gl_FragColor = vec4(vColor, opacity);
    #include <colorspace_fragment>
  }
`;

/** Material for InstancedMesh of threeFaceBoxGeometry(); colours come from instanceColor (linear RGB). */
export function cuboidMaterial({ opacity = 1 } = {}) {
  const transparent = opacity < 1;
  return new THREE.ShaderMaterial({
    uniforms: { opacity: { value: opacity }, zCut: { value: 1e9 } },
    vertexShader,
    fragmentShader,
    side: THREE.DoubleSide, // mirrored faces flip their winding
    transparent,
    depthWrite: !transparent,
  });
}
