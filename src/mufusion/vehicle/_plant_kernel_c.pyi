from mufusion.vehicle.params import TireParams
from mufusion.vehicle.plant_kernel import AxleFloats, Command, PlantKernel, StepResult

class CompiledPlantKernel:
    def __init__(
        self, kernel: PlantKernel, gravity: float, slip_floor: float, slip_step: float
    ) -> None: ...
    def step(
        self,
        chassis0: tuple[float, ...],
        omega_f0: float,
        omega_r0: float,
        command: Command,
        mu_f: float,
        mu_r: float,
        tire_f: TireParams,
        tire_r: TireParams,
        first_axles: tuple[AxleFloats, AxleFloats] | None,
    ) -> StepResult: ...
