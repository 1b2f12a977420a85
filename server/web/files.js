// Uploads are multipart parts named by the path a scene (or an assignment) writes, such as
// "textures/bricks.ppm"; a browser only knows a chosen file's own name. These match the two
// by the file name, so a student picks files without retyping paths.

export function readText(file) {
  return file.text();
}

export function basename(path) {
  return path.slice(path.lastIndexOf('/') + 1);
}

function stem(path) {
  return basename(path).replace(/\.[^.]*$/, '');
}

function dirname(path) {
  const slash = path.lastIndexOf('/');
  return slash < 0 ? '' : path.slice(0, slash);
}

// The words of a scene that could name a file: model-file words and JSON strings alike.
function pathsIn(sceneText) {
  return sceneText.split(/[\s"',:[\]{}]+/).filter((w) => w.includes('.'));
}

// [{file, name}]: each texture file named by the path the scene gives it, else its own name.
export function nameTextures(sceneText, files) {
  const paths = pathsIn(sceneText);
  return [...files].map((file) => ({
    file,
    name: paths.find((p) => basename(p) === file.name) || file.name,
  }));
}

// For POST /grade: the assignment's scenes by the paths its tests give, their textures by
// the scene's folder joined with the path the scene gives (as the server resolves them), and
// the student's images by the tests' image paths. Returns [{file, name}].
export async function nameAssignmentFiles(assignment, sceneFiles, imageFiles) {
  const tests = Array.isArray(assignment.tests) ? assignment.tests : [];
  const named = [];
  const scenes = [];  // {path, text}
  const rest = [];
  for (const file of sceneFiles) {
    const test = tests.find((t) => typeof t.scene === 'string' && basename(t.scene) === file.name);
    if (test) {
      named.push({ file, name: test.scene });
      scenes.push({ path: test.scene, text: await readText(file) });
    } else {
      rest.push(file);
    }
  }
  for (const file of rest) {
    let name = file.name;
    for (const scene of scenes) {
      const path = pathsIn(scene.text).find((p) => basename(p) === file.name);
      if (path) {
        name = dirname(scene.path) ? `${dirname(scene.path)}/${path}` : path;
        break;
      }
    }
    named.push({ file, name });
  }
  // A test's image defaults to its scene's name with .ppm; a PNG stands in for a PPM of the
  // same stem (the server reads either by its content).
  const imageOf = (t) =>
    typeof t.image === 'string' ? t.image : typeof t.scene === 'string' ? stem(t.scene) + '.ppm' : '';
  for (const file of imageFiles) {
    const test =
      tests.find((t) => basename(imageOf(t)) === file.name) ||
      tests.find((t) => stem(imageOf(t)) === stem(file.name));
    named.push({ file, name: test ? imageOf(test) : file.name });
  }
  return named;
}

export function describeNames(named) {
  return named
    .filter(({ file, name }) => file.name !== name)
    .map(({ file, name }) => `${file.name} → ${name}`)
    .join(', ');
}
