; TF5200 programming manual, "Radius programming (R, G163)": the radius in a block of its own (no motion), the motion in the next
; https://infosys.beckhoff.com/content/1033/tccncprogramming/15556764811.html
; adapted: M30 appended.
; expect: end X=100 Y=0
; expect: blocks N10 N20 N30 N40
N10 G90 G01 X0 Y0 F500
N20 G02 R=50 (In this block still no motion)
N30 X100 (Motion block)
N40 M30
