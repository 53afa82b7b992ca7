class CompiledFrames:
    def __init__(
        self,
        anchors: list[tuple[float, float, float, float, float, float, float]],
        gauss: list[tuple[float, float]],
        length_m: float,
    ) -> None: ...
    def frame(self, s: float) -> tuple[float, float, float, float]: ...
    def newton(
        self, px: float, py: float, s: float, max_iterations: int
    ) -> tuple[float, float, float, bool]: ...
