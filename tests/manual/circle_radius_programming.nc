; TF5200 programming manual, "Radius programming (R, G163)": two half circles by radius
; https://infosys.beckhoff.com/content/1033/tccncprogramming/15556764811.html
; adapted: M30 appended.
; expect: end X=200 Y=0
; expect: blocks N10 N20 N30 N40
N10 G90 G01 X0 Y0 F500
N20 G02 X100 R50
N30 G03 X200 R50
N40 M30
