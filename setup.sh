#!/usr/bin/env bash
# Set up ddpy on Debian (as root): system packages, a virtual environment in .venv and the
# package itself (editable, so the Fortran core rebuilds when a source changes).
# Safe to run again: it installs only what is missing.
#
# ./setup.sh --mpi sets up the MPI variant instead (docs/mpi.md): the parallel MUMPS and
# OpenMPI from Debian, its own environment .venv-mpi and build folder build/mpi (meson
# option -Dmumps=mpi), for `mpirun -n N .venv-mpi/bin/ddpy run CASE`. .venv stays sequential.
set -euo pipefail
cd "$(dirname "$0")"

variant=seq
case "${1:-}" in
  "") ;;
  --mpi) variant=mpi ;;
  *) echo "usage: ./setup.sh [--mpi]" >&2; exit 2 ;;
esac

PYTHON=${PYTHON:-python3}
# Compilers and libraries of the core; the X/GL libraries are what the gmsh wheel loads.
packages=(gfortran gcc pkg-config libmumps-seq-dev libopenblas-dev
          libglu1-mesa libgl1 libxrender1 libxcursor1 libxft2 libxinerama1)
venv=.venv
build_args=()
if [ "$variant" = mpi ]; then
  packages+=(libmumps-dev openmpi-bin libopenmpi-dev)
  venv=.venv-mpi
  build_args=(-Csetup-args=-Dmumps=mpi -Cbuild-dir=build/mpi)
fi
if ! "$PYTHON" -c "import ensurepip, venv" 2>/dev/null; then packages+=(python3-venv); fi
if ! "$PYTHON" -c "import sysconfig, os, sys; sys.exit(not os.path.exists(
        os.path.join(sysconfig.get_paths()['include'], 'Python.h')))"; then
  packages+=(python3-dev)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" > /dev/null
fi

[ -x $venv/bin/python ] || "$PYTHON" -m venv $venv
export PATH="$PWD/$venv/bin:$PATH"

# Reinstall only when the dependency list changed or the package is not importable.
stamp=$venv/.ddpy-setup
want=$( (cat pyproject.toml; echo "$variant") | sha256sum | cut -d' ' -f1)
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ] || ! python -c "import ddpy._core" 2>/dev/null; then
  echo "setup: installing Python packages into $venv"
  python -m pip install -q --upgrade pip
  python -m pip install -q "meson-python>=0.15" "meson>=1.3" ninja "numpy>=2.0"
  python -m pip install -q --no-build-isolation "${build_args[@]}" -e ".[test]"
  echo "$want" > "$stamp"
fi
python -c "import ddpy._core" # builds the core if a source changed since the last build
echo "setup: ready (ddpy $(python -c 'import ddpy; print(ddpy.__version__)'), $venv/bin/ddpy)"
