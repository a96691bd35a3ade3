(seed 003 §2.3.2 "Streaming instructions with subroutine invocation": written into the stream)
N10 G01 X200 F1000
N20 X240 Y100
N30 X200 Y0
N40 L subprogram.nc
N50 M30 (added: program end after subprogram.nc returns)
