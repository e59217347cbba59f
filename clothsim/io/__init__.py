"""Files: meshes in, frames, run records and matrices out. Every meshio call of clothsim is
in this package, and meshio is imported only inside the functions that use it, so
``import clothsim`` stays light.

======================  ================================================================
module                  what it reads or writes
======================  ================================================================
``io.meshes``           mesh files: :func:`load_mesh` (read + check), :func:`read_mesh`,
                        :func:`write_mesh`, :func:`supported_formats`
``io.obj``              Wavefront OBJ, clothsim's own reader and writer
``io.cells``            a mesh as the cell blocks mesh files store
``io.frames``           one ``.vtu`` per frame and ``trajectory.pvd``
                        (:class:`FrameWriter`, :func:`read_frame`, :func:`read_pvd`)
``io.frameproc``        a large run's frame files written by a second process
``io.child``            starting and ending such helper processes (frames, pictures)
``io.runfolder``        a run's folder, its one owner (:class:`RunFolder`): frames,
                        trajectory store, run.json, status, resume point
``io.outfolder``        any output folder from claim to final status (:class:`OutputFolder`)
``io.folders``          which folders clothsim may write, their kinds and statuses
``io.lock``             the folder lock ``.clothsim.lock`` (never followed, then removed)
``io.resume``           where ``--resume`` continues
``io.effectstate``      what the effects carry into the next step, per frame
                        (``state/frame_%06d.npz``: held contacts), for ``--resume``
``io.diskspace``        the disk a run needs, estimated before it writes
``io.runfiles``         ``run.json`` and ``trajectory.npz`` of a run, streamed to disk
``io.matrices``         Matrix Market matrices and text vectors for other implementations
``io.assignment``       the scene format of A. Jacobson's mass-spring assignment
``io.common``           atomic writes (:func:`atomic_path`) and a quiet meshio
======================  ================================================================
"""

from .common import atomic_path
from .frames import PVD_NAME, FrameWriter, read_frame, read_pvd
from .matrices import read_matrix, read_vector, write_matrix, write_vector
from .meshes import load_mesh, read_mesh, supported_formats, write_mesh
from .obj import read_obj_cells

__all__ = ["atomic_path", "PVD_NAME", "FrameWriter", "read_frame", "read_pvd", "read_matrix",
           "read_vector", "write_matrix", "write_vector", "load_mesh", "read_mesh",
           "supported_formats", "write_mesh", "read_obj_cells"]
