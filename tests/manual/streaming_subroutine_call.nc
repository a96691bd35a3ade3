; TF5200 data streaming, "Subroutine call": streaming instructions with subroutine invocation
; https://infosys.beckhoff.com/content/1033/tf5200_data_streaming/222573067.html
; run: stream
; adapted: the subroutine, not shown on the page, is one move and M17; M30 appended after the call.
; expect: end X=0 Y=0
; expect: blocks N10 N20 N30 N40 N1 N2
N10 G01 X200 F1000
N20 X240 Y100
N30 X200 Y0
N40 L subprogram.nc
M30
; --- file subprogram.nc
N1 G01 X0
N2 M17
