"""docs/parameters.md against `mtled plugins --markdown`. A build without the CUDA toolkit has no cuda backend
plugin: its section is left out of the comparison then (the committed file documents the full build)."""
import subprocess
import sys

mtled, document, cuda_built = sys.argv[1], sys.argv[2], sys.argv[3] == "ON"
generated = subprocess.run([mtled, "plugins", "--markdown"], capture_output=True, text=True, check=True).stdout
committed = open(document, encoding="utf-8").read()
if not cuda_built:
    start = committed.find("### `cuda`")
    if start >= 0:
        end = committed.find("\n## ", start)
        committed = committed[:start].rstrip("\n") + "\n" + (committed[end:] if end >= 0 else "")
if generated != committed:
    import difflib
    sys.stdout.writelines(difflib.unified_diff(committed.splitlines(True), generated.splitlines(True), document, "generated"))
    sys.exit("docs/parameters.md is stale: run  build/bin/mtled plugins --markdown > docs/parameters.md  (in a build "
             "with the CUDA toolkit, so that the cuda backend is documented)")
