#!/usr/bin/python3
"""docs/your-assets.md's scenes render as a reader copies them.

    tests/docs/test_docs_your_assets.py SOURCE_DIR MESO_PROGRAM

Every ```json block of the page that follows a line naming `examples/your-assets/NAME.json`
must be that file, byte for byte (so the page shows what the test renders), every scene file
of examples/your-assets/ must be on the page, and each scene must render with its own
technique (64 x 64) to a PNG, exit status 0. The tile-mesh scene is also rendered with
--techniques reference,flat, as the page's check does. Fails with one line per problem.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

NAMED_BLOCK = re.compile(r"^`(examples/your-assets/[A-Za-z0-9_.-]+\.json)`:\s*\n\s*\n```json\n(.*?)```",
                         re.M | re.S)


def main():
    if len(sys.argv) != 3:
        print("usage: test_docs_your_assets.py SOURCE_DIR MESO_PROGRAM", file=sys.stderr)
        return 2
    source, meso = sys.argv[1], sys.argv[2]
    page_path = os.path.join(source, "docs", "your-assets.md")
    with open(page_path, encoding="utf-8") as f:
        page = f.read()
    problems = []
    blocks = NAMED_BLOCK.findall(page)
    if len(blocks) < 6:
        problems.append("docs/your-assets.md: %d named scenes, expected at least 6" % len(blocks))
    on_page = set()
    for name, text in blocks:
        on_page.add(name)
        path = os.path.join(source, name)
        if not os.path.exists(path):
            problems.append("docs/your-assets.md: %s: no such file" % name)
            continue
        with open(path, encoding="utf-8") as f:
            if f.read() != text:
                problems.append("docs/your-assets.md: the block of %s differs from the file" % name)
    folder = os.path.join(source, "examples", "your-assets")
    for file_name in sorted(os.listdir(folder)):
        if file_name.endswith(".json") and "examples/your-assets/" + file_name not in on_page:
            problems.append("examples/your-assets/%s: not shown on docs/your-assets.md" % file_name)
    with tempfile.TemporaryDirectory(prefix="meso-your-assets-") as out:
        # a reader's folder: the assets, and each block pasted beside them
        for file_name in os.listdir(folder):
            if not file_name.endswith(".json"):
                shutil.copy(os.path.join(folder, file_name), out)
        for name, text in blocks:
            pasted = os.path.join(out, os.path.basename(name))
            with open(pasted, "w", encoding="utf-8") as f:
                f.write(text)
            png = pasted + ".png"
            run = subprocess.run([meso, "render", pasted, "-o", png, "--size", "64x64", "--quiet"],
                                 capture_output=True, text=True)
            if run.returncode != 0 or not os.path.exists(png) or os.path.getsize(png) == 0:
                problems.append("%s: meso render exited %d: %s" % (name, run.returncode,
                                                                   run.stderr.strip()))
        tile = os.path.join(folder, "tile-solid.json")
        check = os.path.join(out, "check")
        run = subprocess.run([meso, "render", tile, "--techniques", "flat", "-o", check, "--size",
                              "48x48", "--frames", "1", "--quiet"], capture_output=True, text=True)
        if run.returncode != 0 or not os.path.exists(os.path.join(check, "reference.png")):
            problems.append("tile-solid.json: --techniques flat with the reference failed (%d): %s"
                            % (run.returncode, run.stderr.strip()))
    for p in problems:
        print(p)
    if problems:
        return 1
    print("docs/your-assets.md: %d scenes match their files and render" % len(blocks))
    return 0


if __name__ == "__main__":
    sys.exit(main())
