; TF5200 programming manual, "Direct selection/deselection of TRC without block (G239)": example 1
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/207810059.html
; adapted: the "%G239_Demo1.nc" file-name line dropped.
; expect: end X=150 Y=0
N010 G0 X0 Y0 Z0 F1000
N020 G239 (TRC mode)
N030 V.G.WZ_AKT.R = 10
N040 G41 G01 X30 Y20   (Select TRC)
N050 G01 X60
N060 G01 X90
N070 G01 X120
N080 G40 (Deselect TRC without block)
N100 G00 X150 Y0
N110 M30
