; TF5200 programming manual, "Linear interpolation (G01)": incremental dimensional input
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206082059.html
; adapted: starts at P1 with the page's N05; M30 appended.
; expect: end X=120 Y=80 U=90
N05 G00 G90 X40 Y20 U30       ; move to starting point P1
; Incremental dimensional input:
N10 G01 G91 X20 Y40 U10 F1000 ;move from P1 to P2 feedrate 1000 mm/min)
N20 X60 Y20 U50 ;move from P2 to P3 feedrate 1000 mm/min)
N30 M30
