// Loads glTF files with three.js's GLTFLoader (the loader three.js viewers use), in node:
// `node three_load.mjs FILE...`. Prints one JSON line per file: { file, meshes, triangles,
// materials: [{ name, type, color, metalness, roughness, anisotropy, anisotropyRotation,
// clearcoat, clearcoatRoughness, sheen, sheenColor, sheenRoughness, specularIntensity,
// specularColor, ior }],
// userData } and exits 1 when a file
// fails to load. Textures are not decoded (node has no image decoder); files with images fail.
import { readFile } from "node:fs/promises";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";

let failed = false;
const loader = new GLTFLoader();
for (const file of process.argv.slice(2)) {
  try {
    const bytes = await readFile(file);
    const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
    const gltf = await loader.parseAsync(buffer, "");
    let meshes = 0;
    let triangles = 0;
    const materials = new Map();
    gltf.scene.traverse((o) => {
      if (!o.isMesh) return;
      meshes += 1;
      const g = o.geometry;
      triangles += (g.index ? g.index.count : g.attributes.position.count) / 3;
      const m = o.material;
      materials.set(m.uuid, {
        name: m.name,
        type: m.type,
        color: m.color ? m.color.toArray() : null,
        metalness: m.metalness,
        roughness: m.roughness,
        anisotropy: m.anisotropy ?? 0,
        anisotropyRotation: m.anisotropyRotation ?? 0,
        clearcoat: m.clearcoat ?? 0,
        clearcoatRoughness: m.clearcoatRoughness ?? 0,
        sheen: m.sheen ?? 0,
        sheenColor: m.sheenColor ? m.sheenColor.toArray() : [0, 0, 0],
        sheenRoughness: m.sheenRoughness ?? 0,
        specularIntensity: m.specularIntensity ?? 1,
        specularColor: m.specularColor ? m.specularColor.toArray() : [1, 1, 1],
        ior: m.ior ?? 1.5,
        tangents: "tangent" in g.attributes,
        userData: m.userData,
      });
    });
    console.log(JSON.stringify({ file, meshes, triangles, materials: [...materials.values()] }));
  } catch (e) {
    console.log(JSON.stringify({ file, error: String(e) }));
    failed = true;
  }
}
process.exit(failed ? 1 : 0);
