; TF5200 diagnosis, ID 20765 "Double-programmed M-function.": channel-specific double programming
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/252469131.html
; adapted: M30 appended.
; expect: error 20765
N10 G00 X10 M10 M10 (channel-specific technofct.)
N20 M30
