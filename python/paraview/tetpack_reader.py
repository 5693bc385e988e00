"""ParaView reader for tetpack (.tpk) files: an unstructured grid of tets with every point and tet field,
and the file's time steps (TIME values, or 0, 1, 2, ... when it stores none).

In pvpython:
    import tetpack; tetpack.load_paraview_plugin(globals()); r = TetpackReader(FileName="x.tpk")
(plain LoadPlugin(path, ns=globals()) works too where ParaView can load Python plugins: Debian 12's
ParaView 5.11 on Python 3.11 needs the inspect.getargspec shim that load_paraview_plugin applies).
It reads through the `tetpack` Python module (libtetpack): that module must be importable, from the
build tree (PYTHONPATH=build/python) or installed (cmake --install).
"""
import numpy as np
from paraview.util.vtkAlgorithm import smdomain, smhint, smproperty, smproxy
from vtkmodules.util.vtkAlgorithm import VTKPythonAlgorithmBase
from vtkmodules.vtkCommonDataModel import vtkUnstructuredGrid
from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline

import tetpack
from tetpack import vtk_support


@smproxy.reader(name="TetpackReader", label="Tetpack Reader", extensions="tpk",
                file_description="tetpack files")
class TetpackReader(VTKPythonAlgorithmBase):
    def __init__(self):
        VTKPythonAlgorithmBase.__init__(self, nInputPorts=0, nOutputPorts=1, outputType="vtkUnstructuredGrid")
        self._filename = None
        self._times = None
        self._geometry = None  # vtk_support.geometry of the file: the same at every step

    @smproperty.stringvector(name="FileName")
    @smdomain.filelist()
    @smhint.filechooser(extensions="tpk", file_description="tetpack files")
    def SetFileName(self, name):
        if self._filename != name:
            self._filename = name
            self._times = None
            self._geometry = None
            self.Modified()

    def _steps(self):
        """Time values of the file's steps: TIME, else 0..n-1 for the field with the most steps."""
        if self._times is None:
            with tetpack.open(self._filename) as f:
                steps = max([field.steps for field in f.fields], default=1)
                times = f.times
                self._times = np.array(times[:steps] if times else range(steps), dtype=np.float64)
        return self._times

    @smproperty.doublevector(name="TimestepValues", information_only="1", si_class="vtkSITimeStepsProperty")
    def GetTimestepValues(self):
        return self._steps().tolist() if self._filename else None

    def RequestInformation(self, request, inInfo, outInfo):
        executive = vtkStreamingDemandDrivenPipeline
        info = outInfo.GetInformationObject(0)
        info.Remove(executive.TIME_STEPS())
        info.Remove(executive.TIME_RANGE())
        times = self._steps()
        if len(times) > 1:
            for t in times:
                info.Append(executive.TIME_STEPS(), t)
            info.Append(executive.TIME_RANGE(), times[0])
            info.Append(executive.TIME_RANGE(), times[-1])
        return 1

    def RequestData(self, request, inInfo, outInfo):
        info = outInfo.GetInformationObject(0)
        times = self._steps()
        step = 0
        if info.Has(vtkStreamingDemandDrivenPipeline.UPDATE_TIME_STEP()):
            wanted = info.Get(vtkStreamingDemandDrivenPipeline.UPDATE_TIME_STEP())
            step = int(np.argmin(np.abs(times - wanted)))  # the nearest stored step
        output = vtkUnstructuredGrid.GetData(outInfo, 0)
        with tetpack.open(self._filename) as f:
            if self._geometry is None:
                self._geometry = vtk_support.geometry(f)
            vtk_support.fill_grid(output, f, step, self._geometry)
        output.GetInformation().Set(output.DATA_TIME_STEP(), float(times[step]))
        return 1
