"""What the picture tests share: running a command (stopping the test with its output when it fails) and the
uniaxial Ogden cube's run, whose exact answer they check the pictures against."""
import subprocess
import sys


def run(command):
    done = subprocess.run([str(c) for c in command], capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{' '.join(map(str, command))} failed:\n{done.stdout}{done.stderr}")
    return done.stdout


def run_ogden_cube(mtled, source, folder):
    """share/scenes/uniaxial_cube_ogden.json run into `folder`: the 10 mm cube compressed to 8 mm."""
    run([mtled, "run", source / "share/scenes/uniaxial_cube_ogden.json", "-o", folder, "--no-progress"])
    return folder
