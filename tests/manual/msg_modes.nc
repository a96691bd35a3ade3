; TF5200 programming manual, "Programming a message (#MSG)"
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/507845131.html
; adapted: M30 appended.
; expect: msg "Text_1"
; expect: msg "Text_3"
; expect: msg "Text_2"
; expect: msg "Text_4"
; expect: msg "Text_5"
#MSG HMI ["Text_1"]
#MSG SYN HMI ["Text_2"]
#MSG ["Text_3"]
#MSG SYN ["Text_4"]
#MSG SYN_ACK ["Text_5"]
M30
